//! SPEC §8 in the library: tiles and sample batches written by `render_exr` and put back
//! together by `merge_exr` equal the one-machine render (tiles bit for bit, batches to
//! rounding), every averaged pass included; and every refusal names its part and writes
//! nothing.

mod common;

use aperture_imageio::{read_exr, Image, MetaValue};
use aperture_output::merge::{merge_exr, MergeError, MergeOptions};
use aperture_output::ExrOptions;
use aperture_render::{AdaptiveOptions, PassSet, RenderOptions, Window};
use aperture_scene::Scene;
use aperture_shading::{test_scenes, Environment};
use glam::Vec3;
use std::path::{Path, PathBuf};

fn opts() -> RenderOptions {
    RenderOptions {
        width: 40,
        height: 30,
        spp: 16,
        passes: PassSet::all(),
        env: Environment::Constant(Vec3::splat(0.3)),
        ..RenderOptions::default()
    }
}

/// A scratch folder, removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Self {
        let dir =
            std::env::temp_dir().join(format!("aperture-merge-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }

    fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    /// Every file in the folder (temporary ones included).
    fn files(&self) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(&self.0)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Renders `o` (only `region`, band `tile`) to `path`.
fn render_part(scene: &Scene, o: &RenderOptions, path: &Path, region: Option<Window>) {
    let exr = ExrOptions {
        region,
        ..ExrOptions::default()
    };
    common::write_exr(scene, o, path, &exr, None, &|_, _| {}).unwrap();
}

/// Renders band K of N for every K, returning the paths.
fn render_tiles(scene: &Scene, o: &RenderOptions, dir: &Scratch, n: u32) -> Vec<PathBuf> {
    (0..n)
        .map(|k| {
            let path = dir.path(&format!("tile-{k}.exr"));
            let exr = ExrOptions {
                region: Window::band(k, n, o.width, o.height),
                tile: Some((k, n)),
                ..ExrOptions::default()
            };
            common::write_exr(scene, o, &path, &exr, None, &|_, _| {}).unwrap();
            path
        })
        .collect()
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|f| f.to_bits()).collect()
}

/// Every pixel of `whole`'s beauty and layers equals `merged`'s, bit for bit.
fn assert_bit_identical(merged: &Image, whole: &Image) {
    assert_eq!((merged.width, merged.height), (whole.width, whole.height));
    assert_eq!(merged.placement, None);
    assert!(
        bits(merged.rgba.as_flattened()) == bits(whole.rgba.as_flattened()),
        "beauty"
    );
    for layer in &whole.layers {
        let m = merged
            .layer(&layer.name)
            .unwrap_or_else(|| panic!("merged lacks {}", layer.name));
        assert_eq!(m.channels, layer.channels);
        assert!(bits(&m.data) == bits(&layer.data), "layer {}", layer.name);
    }
}

#[test]
fn tiles_merge_into_the_whole_render_bit_for_bit() {
    let dir = Scratch::new("tiles");
    let s = test_scenes::passes();
    for adaptive in [false, true] {
        let mut o = opts();
        o.adaptive = adaptive.then_some(AdaptiveOptions {
            threshold: 0.05,
            min_spp: 4,
        });
        let whole_path = dir.path("whole.exr");
        render_part(&s, &o, &whole_path, None);
        let whole = read_exr(&whole_path).unwrap();
        let mut tiles = render_tiles(&s, &o, &dir, 4);
        // Arguments in any order: tile-3 first.
        tiles.reverse();
        let out = dir.path("merged.exr");
        let summary = merge_exr(&tiles, &out, &MergeOptions::default()).unwrap();
        assert_eq!((summary.parts, summary.windows), (4, 4));
        assert!(summary.complete);
        let merged = read_exr(&out).unwrap();
        assert_bit_identical(&merged, &whole);
        let counts = &merged.layer("Debug Sample Count").unwrap().data;
        if adaptive {
            assert!(
                counts.contains(&4.0) && counts.contains(&16.0),
                "adaptive varies"
            );
        } else {
            assert!(counts.iter().all(|&c| c == 16.0));
        }
        assert_eq!(
            merged.meta("aperture:mergedParts"),
            Some(&MetaValue::Int(4))
        );
        assert_eq!(merged.meta("aperture:region"), None);
        assert_eq!(merged.meta("aperture:tile"), None);
        assert_eq!(merged.meta("aperture:spp"), Some(&MetaValue::Int(16)));
        // A grid of tiles (--region) too, one of them 1 pixel wide.
        let grid = [
            (0, 0, 17, 13),
            (17, 0, 39, 13),
            (39, 0, 40, 13),
            (0, 13, 40, 30),
        ];
        let parts: Vec<PathBuf> = grid
            .iter()
            .enumerate()
            .map(|(i, &(x0, y0, x1, y1))| {
                let p = dir.path(&format!("region-{i}.exr"));
                render_part(&s, &o, &p, Window::from_corners(x0, y0, x1, y1));
                p
            })
            .collect();
        merge_exr(&parts, &out, &MergeOptions::default()).unwrap();
        assert_bit_identical(&read_exr(&out).unwrap(), &whole);
    }
}

/// Relative difference of two values, against the larger.
fn rel(a: f32, b: f32) -> f64 {
    rel_px(&[a], &[b])
}

/// Largest difference of two pixels' values, relative to the largest magnitude among them
/// (a signed vector such as a mean normal can have a component near 0 by cancellation).
fn rel_px(a: &[f32], b: &[f32]) -> f64 {
    let scale = a
        .iter()
        .chain(b)
        .map(|v| f64::from(*v).abs())
        .fold(0.0, f64::max);
    let diff = a
        .iter()
        .zip(b)
        .map(|(x, y)| (f64::from(*x) - f64::from(*y)).abs())
        .fold(0.0, f64::max);
    if diff == 0.0 {
        0.0
    } else {
        diff / scale
    }
}

/// The largest relative difference between a merge and the one render, and where: averaged
/// passes to rounding; per-pixel passes (depth, position) and Cryptomatte IDs exactly (asserted).
fn worst_difference(merged: &Image, whole: &Image) -> (f64, String) {
    let mut worst = (0.0f64, String::new());
    let mut note = |d: f64, what: &str| {
        if d > worst.0 {
            worst = (d, what.to_string());
        }
    };
    for (m, w) in merged.rgba.iter().zip(&whole.rgba) {
        for c in 0..4 {
            note(rel(m[c], w[c]), "beauty");
        }
    }
    for layer in &whole.layers {
        let m = &merged.layer(&layer.name).unwrap().data;
        if layer.name.starts_with("Crypto") {
            for (i, (a, b)) in m.iter().zip(&layer.data).enumerate() {
                if i % 2 == 0 {
                    assert_eq!(a.to_bits(), b.to_bits(), "{} id at {i}", layer.name);
                } else {
                    note(rel(*a, *b), &layer.name);
                }
            }
        } else if matches!(layer.name.as_str(), "Depth" | "Position") {
            assert!(bits(m) == bits(&layer.data), "{}", layer.name);
        } else {
            let n = layer.channels.len();
            for (a, b) in m.chunks_exact(n).zip(layer.data.chunks_exact(n)) {
                note(rel_px(a, b), &layer.name);
            }
        }
    }
    worst
}

/// The merged light passes still add up to the merged beauty (as each render's do).
fn assert_light_passes_add_up(merged: &Image) {
    let rgb = |name: &str, p: usize| {
        let l = merged.layer(name).unwrap();
        Vec3::from_slice(&l.data[p * 3..p * 3 + 3])
    };
    let mut lit = 0;
    for (p, px) in merged.rgba.iter().enumerate() {
        let mut sum = rgb("Emission", p) + rgb("Environment", p);
        for lobe in ["Diffuse", "Glossy", "Transmission"] {
            let colour = rgb(&format!("{lobe} Color"), p);
            sum +=
                (rgb(&format!("{lobe} Direct"), p) + rgb(&format!("{lobe} Indirect"), p)) * colour;
        }
        let beauty = Vec3::new(px[0], px[1], px[2]);
        assert!(
            (sum - beauty).abs().max_element() <= 1e-4 * beauty.max_element().max(1.0),
            "pixel {p}: passes {sum} vs beauty {beauty}"
        );
        lit += usize::from(beauty.max_element() > 0.0);
    }
    assert!(lit > 100);
}

#[test]
fn sample_batches_merge_into_the_longer_render() {
    let dir = Scratch::new("batches");
    let s = test_scenes::passes();
    let whole_opts = RenderOptions { spp: 24, ..opts() };
    let whole_path = dir.path("whole.exr");
    render_part(&s, &whole_opts, &whole_path, None);
    let whole = read_exr(&whole_path).unwrap();
    // Unequal batches: 0..8, 8..16, 16..24, listed out of order.
    let parts: Vec<PathBuf> = [16, 0, 8]
        .iter()
        .map(|&offset| {
            let p = dir.path(&format!("batch-{offset}.exr"));
            let o = RenderOptions {
                spp: 8,
                sample_offset: offset,
                ..opts()
            };
            render_part(&s, &o, &p, None);
            p
        })
        .collect();
    let out = dir.path("merged.exr");
    let summary = merge_exr(&parts, &out, &MergeOptions::default()).unwrap();
    assert_eq!(
        (summary.windows, summary.sample_ranges.as_str()),
        (1, "0-24")
    );
    let merged = read_exr(&out).unwrap();
    assert_eq!(merged.meta("aperture:spp"), Some(&MetaValue::Int(24)));
    assert_eq!(
        merged.meta("aperture:sampleOffset"),
        Some(&MetaValue::Int(0))
    );
    assert!(merged
        .layer("Debug Sample Count")
        .unwrap()
        .data
        .iter()
        .all(|&c| c == 24.0));

    let worst = worst_difference(&merged, &whole);
    eprintln!(
        "largest relative difference, 3 batches vs one render: {:.3e} ({})",
        worst.0, worst.1
    );
    assert!(worst.0 < 1e-6, "{worst:?}");

    assert_light_passes_add_up(&merged);
}

#[test]
fn tiles_of_batches_merge_too() {
    let dir = Scratch::new("tiles-of-batches");
    let s = test_scenes::passes();
    let whole_path = dir.path("whole.exr");
    render_part(&s, &opts(), &whole_path, None);
    let whole = read_exr(&whole_path).unwrap();
    let mut parts = Vec::new();
    for k in 0..2 {
        for offset in [0, 8] {
            let p = dir.path(&format!("t{k}-s{offset}.exr"));
            let o = RenderOptions {
                spp: 8,
                sample_offset: offset,
                ..opts()
            };
            render_part(&s, &o, &p, Window::band(k, 2, 40, 30));
            parts.push(p);
        }
    }
    let out = dir.path("merged.exr");
    let summary = merge_exr(&parts, &out, &MergeOptions::default()).unwrap();
    assert_eq!((summary.parts, summary.windows), (4, 2));
    let merged = read_exr(&out).unwrap();
    for (m, w) in merged.rgba.iter().zip(&whole.rgba) {
        for c in 0..4 {
            assert!(rel(m[c], w[c]) < 1e-6, "{m:?} vs {w:?}");
        }
    }
    // A merged file merges again: its sample range is in its header.
    let more = dir.path("batch-16.exr");
    let o = RenderOptions {
        spp: 8,
        sample_offset: 16,
        ..opts()
    };
    render_part(&s, &o, &more, None);
    let again = dir.path("again.exr");
    let summary = merge_exr(&[out.clone(), more], &again, &MergeOptions::default()).unwrap();
    assert_eq!(summary.sample_ranges, "0-24");
    let again = read_exr(&again).unwrap();
    assert_eq!(again.meta("aperture:mergedParts"), Some(&MetaValue::Int(5)));
    assert_eq!(again.meta("aperture:spp"), Some(&MetaValue::Int(24)));
    // ... but not with samples it already holds.
    let overlapping = dir.path("batch-8.exr");
    let o = RenderOptions {
        spp: 8,
        sample_offset: 8,
        ..opts()
    };
    render_part(&s, &o, &overlapping, None);
    let err = merge_exr(
        &[out.clone(), overlapping],
        &dir.path("twice.exr"),
        &MergeOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(err, MergeError::OverlappingSamples { .. }),
        "{err}"
    );
}

/// Runs a merge that must fail: the error names `culprit`, and nothing is written (no
/// output, no temporary file).
fn refused(dir: &Scratch, parts: &[PathBuf], culprit: &str) -> MergeError {
    let before = dir.files();
    let out = dir.path("out.exr");
    let err = merge_exr(parts, &out, &MergeOptions::default()).unwrap_err();
    assert!(
        err.to_string().contains(culprit),
        "the error does not name {culprit}: {err}"
    );
    assert_eq!(dir.files(), before, "something was written");
    err
}

/// A small render of the passes scene (4 samples, compositing passes) in three tiles, in a
/// new scratch folder: the scene, its options, the folder and the tiles.
fn refusal_tiles(name: &str) -> (Scene, RenderOptions, Scratch, Vec<PathBuf>) {
    let dir = Scratch::new(name);
    let s = test_scenes::passes();
    let small = RenderOptions {
        spp: 4,
        passes: PassSet::compositing(),
        ..opts()
    };
    let tiles = render_tiles(&s, &small, &dir, 3);
    (s, small, dir, tiles)
}

/// Parts of another scene, pose or options are refused, each named.
#[test]
fn merge_refuses_parts_that_do_not_belong_together() {
    let (s, small, dir, tiles) = refusal_tiles("refusals");
    // Another scene.
    let mut other = s.clone();
    other.source_hash ^= 1;
    let foreign = dir.path("foreign-scene.exr");
    render_part(&other, &small, &foreign, Window::band(1, 3, 40, 30));
    let err = refused(
        &dir,
        &[tiles[0].clone(), foreign, tiles[2].clone()],
        "foreign-scene.exr",
    );
    assert!(matches!(err, MergeError::OtherScene { .. }), "{err}");

    // The same file in another pose (another --time).
    let mut later = s.clone();
    later.stats.time = Some(1.5);
    let posed = dir.path("frame-36.exr");
    render_part(&later, &small, &posed, Window::band(1, 3, 40, 30));
    let err = refused(
        &dir,
        &[tiles[0].clone(), posed, tiles[2].clone()],
        "frame-36.exr",
    );
    assert!(matches!(err, MergeError::OtherPose { .. }), "{err}");
    assert!(err.to_string().contains("t=1.5"), "{err}");

    // Other options (another seed).
    let seeded = dir.path("seed-7.exr");
    let o = RenderOptions {
        seed: 7,
        ..small.clone()
    };
    render_part(&s, &o, &seeded, Window::band(1, 3, 40, 30));
    let err = refused(
        &dir,
        &[tiles[0].clone(), seeded, tiles[2].clone()],
        "seed-7.exr",
    );
    assert!(matches!(err, MergeError::OtherOptions { .. }), "{err}");
}

/// Overlapping samples or windows and missing tiles or batches are refused, each named.
#[test]
fn merge_refuses_overlaps_and_gaps() {
    let (s, small, dir, tiles) = refusal_tiles("refusals-overlaps");
    // Overlapping sample ranges: 0..4 and 2..6.
    let overlap = dir.path("offset-2.exr");
    let o = RenderOptions {
        sample_offset: 2,
        ..small.clone()
    };
    render_part(&s, &o, &overlap, Window::band(1, 3, 40, 30));
    let err = refused(&dir, &[tiles[1].clone(), overlap], "offset-2.exr");
    assert!(
        matches!(err, MergeError::OverlappingSamples { .. }),
        "{err}"
    );
    assert!(err.to_string().contains("tile-1.exr"), "{err}");

    // A missing tile: named by its region and by its --tile.
    let err = refused(&dir, &[tiles[2].clone(), tiles[0].clone()], "--tile 1/3");
    assert!(err.to_string().contains("0,10,40,20"), "{err}");

    // A missing batch in one window.
    let batch = dir.path("tile-0-batch-4.exr");
    let o = RenderOptions {
        sample_offset: 4,
        ..small.clone()
    };
    render_part(&s, &o, &batch, Window::band(0, 3, 40, 30));
    let mut with_batch = tiles.clone();
    with_batch.push(batch);
    let err = refused(&dir, &with_batch, "tile-1.exr");
    assert!(matches!(err, MergeError::MissingSamples { .. }), "{err}");

    // Windows that overlap without being equal.
    let shifted = dir.path("shifted.exr");
    render_part(&s, &small, &shifted, Window::from_corners(0, 5, 40, 15));
    let err = refused(&dir, &[tiles[0].clone(), shifted], "shifted.exr");
    assert!(
        matches!(err, MergeError::OverlappingRegions { .. }),
        "{err}"
    );
}

/// With --allow-partial, a merge with a tile missing writes what there is.
#[test]
fn partial_merge_leaves_missing_tiles_empty() {
    let (_, _, dir, tiles) = refusal_tiles("refusals-partial");
    // With --allow-partial, what there is: the bounding box, uncovered pixels empty.
    let out = dir.path("partial.exr");
    let partial = MergeOptions {
        allow_partial: true,
    };
    let summary = merge_exr(&[tiles[2].clone(), tiles[0].clone()], &out, &partial).unwrap();
    assert!(!summary.complete);
    let image = read_exr(&out).unwrap();
    assert_eq!((image.width, image.height, image.placement), (40, 30, None));
    let counts = &image.layer("Debug Sample Count").unwrap().data;
    assert_eq!(counts[15 * 40], 0.0, "a pixel of the missing tile");
    assert_eq!(counts[5 * 40], 4.0);
}

#[test]
fn merge_refuses_damaged_parts_naming_them() {
    let dir = Scratch::new("damaged");
    let s = test_scenes::passes();
    let small = RenderOptions { spp: 2, ..opts() };
    let tiles = render_tiles(&s, &small, &dir, 2);
    let bytes = std::fs::read(&tiles[1]).unwrap();
    let cases: [(&str, Vec<u8>); 4] = [
        ("truncated.exr", bytes[..bytes.len() * 2 / 3].to_vec()),
        ("header-cut.exr", bytes[..100].to_vec()),
        ("empty.exr", Vec::new()),
        ("garbage.exr", {
            let mut b = bytes.clone();
            let n = b.len();
            for v in &mut b[n / 2..n / 2 + 2000] {
                *v = 0x5a;
            }
            b
        }),
    ];
    for (name, data) in cases {
        let path = dir.path(name);
        std::fs::write(&path, data).unwrap();
        let err = refused(&dir, &[tiles[0].clone(), path.clone()], name);
        assert!(matches!(err, MergeError::Read { .. }), "{name}: {err}");
        std::fs::remove_file(&path).unwrap();
    }
    // A missing file, and an EXR that no aperture render wrote.
    let err = refused(
        &dir,
        &[tiles[0].clone(), dir.path("absent.exr")],
        "absent.exr",
    );
    assert!(matches!(err, MergeError::Read { .. }), "{err}");
    let plain = dir.path("plain.exr");
    aperture_imageio::write_exr(&plain, &Image::new(40, 15)).unwrap();
    let err = refused(&dir, &[tiles[0].clone(), plain], "plain.exr");
    assert!(matches!(err, MergeError::NotAPart { .. }), "{err}");
    // The output may not be one of the parts.
    let err = merge_exr(&tiles, &tiles[0], &MergeOptions::default()).unwrap_err();
    assert!(matches!(err, MergeError::OutputIsAPart { .. }), "{err}");
    assert!(matches!(
        merge_exr(&[], &dir.path("none.exr"), &MergeOptions::default()),
        Err(MergeError::NoParts)
    ));
}
