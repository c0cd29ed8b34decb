//! `KHR_texture_basisu`: KTX2 textures transcoded against the same textures as JPEG and PNG
//! (the two StainedGlassLamp samples: one with KTX2 only, one with the originals), and whole
//! files that use or require the extension.

mod common;

use aperture_scene::{decode_texture, load, Error, LoadOptions, Texels};

fn rgba8(t: &Texels) -> &[[u8; 4]] {
    match t {
        Texels::Rgba8(v) => v,
        Texels::Rgba32F(_) => panic!("an 8-bit texture decoded as float"),
    }
}

/// Each KTX2 image of the KTX sample against the original it was encoded from: the same size,
/// per-channel means within 1 % of full scale and a mean absolute difference under 2 % (Basis
/// Universal is lossy; a wrong channel order, orientation or colour space fails both).
#[test]
fn transcoded_textures_match_their_originals() {
    let Some(dir) = common::samples_dir() else {
        return;
    };
    let ktx = dir.join("unsupported/StainedGlassLamp-KTX-BasisU");
    let orig = dir.join("benchmark/StainedGlassLamp");
    let mut compared = 0;
    for name in [
        "StainedGlassLamp_base_basecolor",
        "StainedGlassLamp_glass_basecolor-alpha",
        "StainedGlassLamp_grill_basecolor-alpha",
        "StainedGlassLamp_hardware_normal",
        "StainedGlassLamp_base_occlusion-rough-metal",
    ] {
        let k = std::fs::read(ktx.join(format!("{name}.ktx2"))).unwrap();
        let o = ["png", "jpg"]
            .iter()
            .find_map(|e| std::fs::read(orig.join(format!("{name}.{e}"))).ok())
            .unwrap_or_else(|| panic!("{name}: no original"));
        let (kw, kh, kt) = decode_texture(&k, 0, u64::MAX).unwrap();
        let (ow, oh, ot) = decode_texture(&o, 1, u64::MAX).unwrap();
        assert_eq!((kw, kh), (ow, oh), "{name}");
        let (kt, ot) = (rgba8(&kt), rgba8(&ot));
        let n = kt.len() as f64;
        let mut mean = [[0.0f64; 4]; 2];
        let mut abs = 0.0f64;
        for (a, b) in kt.iter().zip(ot) {
            for c in 0..4 {
                mean[0][c] += f64::from(a[c]) / 255.0 / n;
                mean[1][c] += f64::from(b[c]) / 255.0 / n;
                abs += (f64::from(a[c]) - f64::from(b[c])).abs() / 255.0 / (4.0 * n);
            }
        }
        let worst = (0..4)
            .map(|c| (mean[0][c] - mean[1][c]).abs())
            .fold(0.0, f64::max);
        println!(
            "{name}: {kw}x{kh}, channel means differ by at most {worst:.4}, mean |diff| {abs:.4}"
        );
        assert!(
            worst < 0.01,
            "{name}: means {:?} against {:?}",
            mean[0],
            mean[1]
        );
        assert!(abs < 0.02, "{name}: mean |diff| {abs}");
        compared += 1;
    }
    assert_eq!(compared, 5);
}

/// A file that requires the extension loads with every texture, and draws what its twin with
/// the original images draws; a file whose textures point at KTX2 images directly loads too.
#[test]
fn files_with_ktx2_textures_load_with_their_textures() {
    let Some(dir) = common::samples_dir() else {
        return;
    };
    let ktx_path = dir.join("unsupported/StainedGlassLamp-KTX-BasisU/StainedGlassLamp.gltf");
    let ktx = load(&ktx_path, &LoadOptions::default()).unwrap();
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&ktx_path).unwrap()).unwrap();
    let orig = load(
        &dir.join("benchmark/StainedGlassLamp/StainedGlassLamp.gltf"),
        &LoadOptions::default(),
    )
    .unwrap();
    // Every image is a KTX2 file, each behind one texture (the twin packs its maps differently).
    assert_eq!(ktx.textures.len(), json["images"].as_array().unwrap().len());
    assert_eq!(ktx.drawn_triangle_count(), orig.drawn_triangle_count());
    assert!(
        ktx.stats.warnings.iter().all(|w| !w.contains("basisu")),
        "{:?}",
        ktx.stats.warnings
    );
    for t in &ktx.textures {
        let texels = rgba8(&t.texels);
        assert_eq!(
            texels.len() as u64,
            u64::from(t.width) * u64::from(t.height)
        );
        assert!(texels.iter().any(|p| p != &texels[0]), "a constant texture");
    }
    let barn = load(
        &dir.join("compression/AnisotropyBarnLamp-KTX2-Basisu/AnisotropyBarnLamp.gltf"),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(barn.textures.len(), 4);
}

/// A KTX2 texture is sized from its header and held to the budget before it is transcoded.
#[test]
fn a_ktx2_texture_is_held_to_the_budget() {
    let Some(dir) = common::samples_dir() else {
        return;
    };
    let k = std::fs::read(
        dir.join("unsupported/StainedGlassLamp-KTX-BasisU/StainedGlassLamp_base_basecolor.ktx2"),
    )
    .unwrap();
    let (w, h, _) = decode_texture(&k, 4, u64::MAX).unwrap();
    let needed = u64::from(w) * u64::from(h) * 12;
    let e = decode_texture(&k, 4, needed - 1).unwrap_err();
    assert!(matches!(e, Error::OverBudget { .. }), "{e}");
    assert!(e.to_string().contains("images[4]"), "{e}");
    decode_texture(&k, 4, needed).unwrap();
    // Truncated: an error naming the image, never a panic.
    for len in [12, 80, k.len() / 2, k.len() - 1] {
        let e = decode_texture(&k[..len], 9, u64::MAX).unwrap_err();
        assert!(e.to_string().contains("images[9]"), "{len}: {e}");
    }
    // Damaged bytes (a fixed pseudo-random sequence of flips, mostly in the header and level
    // index): an answer or an error for each, never a panic.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for round in 0..200 {
        let mut d = k.clone();
        for _ in 0..1 + round % 4 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let at = if round % 2 == 0 {
                state as usize % 256
            } else {
                state as usize % d.len()
            };
            d[at] ^= 1 << ((state >> 40) % 8);
        }
        if let Err(e) = decode_texture(&d, 9, 64 << 20) {
            assert!(e.to_string().contains("images[9]"), "{round}: {e}");
        }
    }
}

/// Fuzz target `texture`, 21,319 executions in (AddressSanitizer: an allocation of 0x12ffffff0000
/// bytes): a KTX2 file whose level 0 claims 20 TB of zstd-inflated data (one damaged length in
/// the level index; the transcoder allocates what is claimed). Made here from the sample it was
/// mutated from: refused from the level index, naming the image and the level.
#[test]
fn a_level_claiming_terabytes_is_refused_before_transcoding() {
    let Some(dir) = common::samples_dir() else {
        return;
    };
    let mut k = std::fs::read(dir.join(
        "unsupported/StainedGlassLamp-KTX-BasisU/StainedGlassLamp_steel_occlusion-rough-metal.ktx2",
    ))
    .unwrap();
    decode_texture(&k, 2, u64::MAX).unwrap();
    // Level 0's uncompressedByteLength: the third u64 of the level index at byte 80.
    k[96..104].copy_from_slice(&20_890_720_862_208u64.to_le_bytes());
    let e = decode_texture(&k, 2, u64::MAX).unwrap_err().to_string();
    assert!(e.contains("images[2]") && e.contains("level 0"), "{e}");
}
