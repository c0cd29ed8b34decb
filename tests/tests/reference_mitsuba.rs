//! Agreement with an independent renderer: Mitsuba 3 (`scalar_rgb`, `path` integrator,
//! `thinlens` sensor) rendered the scenes of `assets/reference/` (see
//! `tools/reference/README.md`); aperture renders the same glTF files as two-sided Lambertian
//! (`--override-material diffuse`), 1-pixel box filter, the same bounce limit and environment,
//! and the two images must agree within noise. The glass scenes (issue 14) keep their own
//! materials: a refractive sphere, smooth (Mitsuba `dielectric`) and rough (`roughdielectric`,
//! GGX, α = roughness²; rendered here without energy compensation, which Mitsuba's
//! single-scattering model does not have), and a block absorbing by Beer–Lambert (`dielectric`
//! boundary around a `homogeneous` medium, σs = 0, `volpath`), on a textured ground.
//!
//! Noise model. Two renders of ours with different seeds, `a` and `b`, are independent
//! estimates of the same image, so `rmse(a, b)² = 2 σ²` where σ is the noise RMSE of one
//! render. We compare their average `(a + b) / 2`, whose noise RMSE is `σ / √2 = rmse(a, b) / 2`.
//! The reference is itself the average of two independent Mitsuba halves and carries its own
//! noise `σ_ref = rmse(half₀, half₁) / 2`, measured by the script and stored in the manifest.
//! Without bias, `rmse(ours, ref)² = σ_ours² + σ_ref²` (independent errors add in quadrature).
//!
//! Tolerances.
//! - `rmse(ours, ref) ≤ 1.25 · sqrt(σ_ours² + σ_ref²)`. A systematic per-pixel error δ (RMS)
//!   adds as `sqrt(σ² + δ²)`, so this catches any bias above 0.75 σ. The 25% margin covers the
//!   uncertainty of the noise estimate itself, which is small here: it averages 57 600 values.
//! - The same rule on 4×4 block means (40×30 values per channel). At 64 spp the per-pixel check
//!   alone is weak: a 10% larger aperture, a focal plane 4.5% too far or one bounce fewer raise
//!   the per-pixel ratio rmse / expected only to 1.02–1.23, all passing. Those errors are
//!   smooth over several pixels while noise is not, so averaging blocks cuts the noise 4× and
//!   keeps most of the error: the block ratio becomes 1.32–2.08 in `dof_point` and `dof_area`
//!   (`dof_env`, lit by a smooth sky, reacts less to the lens: 1.11–1.12), while the renderer
//!   as it is stays at 0.87–1.02 (measured; docs/accuracy.md).
//! - Each channel's image mean within 0.5% of the reference's. The image mean averages
//!   19 200 pixels × 2·spp samples: its own noise is below 0.05% in every scene (measured), so
//!   0.5% is a bias detector for the light units (683 cd/W, emissive strength) and the
//!   environment, not a noise allowance. (One bounce fewer moves the means by only 0.1–0.5%
//!   here; the block check catches it: block ratios 1.7–2.5.)

use aperture_imageio::{metrics, read_exr, Image};
use aperture_render::{build_accel, render, FilterKind, RenderOptions};
use aperture_scene::LoadOptions;
use aperture_shading::MaterialOverride;
use glam::Vec3;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// `rmse(ours, ref)` may exceed the noise-only expectation by this factor.
const RMSE_FACTOR: f64 = 1.25;
/// Largest allowed `|mean_ours / mean_ref − 1|` per channel.
const MEAN_TOLERANCE: f64 = 0.005;
/// Side of the pixel blocks of the second RMSE check.
const BLOCK: u32 = 4;

fn reference_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/reference")
}

fn manifest_entry(name: &str) -> Value {
    let path = reference_dir().join("manifest.json");
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
    let manifest: Value = serde_json::from_str(&text).expect("manifest.json is JSON");
    manifest["scenes"]
        .as_array()
        .expect("manifest has a scenes array")
        .iter()
        .find(|s| s["name"] == name)
        .unwrap_or_else(|| panic!("{name} is not in manifest.json"))
        .clone()
}

fn as_u32(v: &Value, key: &str) -> u32 {
    v[key]
        .as_u64()
        .and_then(|x| u32::try_from(x).ok())
        .unwrap_or_else(|| panic!("manifest: {key} is not a u32: {}", v[key]))
}

fn as_f64(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("manifest: {key} is not a number: {}", v[key]))
}

/// Our average against the reference at one scale.
#[derive(Debug, Clone, Copy)]
struct Comparison {
    /// `rmse(ours, reference)`.
    rmse: f64,
    /// Noise RMSE of our average, `rmse(a, b) / 2`.
    noise_ours: f64,
    /// Noise RMSE of the reference.
    noise_ref: f64,
}

impl Comparison {
    /// `rmse(a, b) / 2` for our two renders `a`, `b` and their average against the reference.
    fn new(a: &Image, b: &Image, average: &Image, reference: &Image, noise_ref: f64) -> Self {
        Self {
            rmse: metrics::rmse(average, reference).expect("same size"),
            noise_ours: metrics::rmse(a, b).expect("same size") / 2.0,
            noise_ref,
        }
    }

    /// The RMSE expected from noise alone.
    fn expected(&self) -> f64 {
        self.noise_ours.hypot(self.noise_ref)
    }

    fn passes(&self) -> bool {
        self.rmse <= RMSE_FACTOR * self.expected()
    }

    fn report(&self) -> String {
        format!(
            "rmse {:.5}, noise ours {:.5}, reference {:.5}, expected {:.5}, limit {:.5} \
             (rmse / expected = {:.3})",
            self.rmse,
            self.noise_ours,
            self.noise_ref,
            self.expected(),
            RMSE_FACTOR * self.expected(),
            self.rmse / self.expected()
        )
    }
}

/// The figures one scene produced.
struct Agreement {
    /// Pixel by pixel.
    full: Comparison,
    /// On `BLOCK`×`BLOCK` pixel averages.
    block: Comparison,
    /// Full-resolution RMSE against the left-right mirrored reference.
    rmse_mirrored: f64,
    /// Per-channel image mean, ours over the reference's.
    ratios: [f64; 3],
}

fn image_of(width: u32, height: u32, rgba: Vec<[f32; 4]>) -> Image {
    let mut im = Image::new(width, height);
    im.rgba = rgba;
    im
}

/// Averages `k`×`k` pixel blocks (the size must divide by `k`).
fn downsample(im: &Image, k: u32) -> Image {
    assert!(im.width % k == 0 && im.height % k == 0);
    let (w, h) = (im.width / k, im.height / k);
    let mut out = vec![[0.0f32; 4]; (w * h) as usize];
    let weight = 1.0 / (k * k) as f32;
    for (i, p) in im.rgba.iter().enumerate() {
        let (x, y) = (i as u32 % im.width, i as u32 / im.width);
        let o = &mut out[((y / k) * w + x / k) as usize];
        for (oc, pc) in o.iter_mut().zip(p) {
            *oc += pc * weight;
        }
    }
    image_of(w, h, out)
}

/// The manifest's constant environment radiance (`null`: black).
fn env_of(name: &str, entry: &Value) -> Vec3 {
    match &entry["env"] {
        Value::Null => Vec3::ZERO,
        Value::Array(c) => {
            let c: Vec<f32> = c
                .iter()
                .map(|x| x.as_f64().expect("env component") as f32)
                .collect();
            Vec3::new(c[0], c[1], c[2])
        }
        other => panic!("{name}: env must be null or [r, g, b], got {other}"),
    }
}

/// The options of our renders, one per seed: samples per pixel (manifest `test_spp`, 64: the
/// four scenes × two seeds × 160×120 px take about 25 s in the dev profile on two cores) and
/// the two seeds whose disagreement measures our noise.
fn render_options(name: &str, entry: &Value) -> Vec<RenderOptions> {
    // `APERTURE_REFERENCE_SPP` raises it to look closer (the tolerances scale with the noise).
    let spp = match std::env::var("APERTURE_REFERENCE_SPP") {
        Ok(v) => v.parse().expect("APERTURE_REFERENCE_SPP is a number"),
        Err(_) => as_u32(entry, "test_spp"),
    };
    let seeds: Vec<u32> = entry["test_seeds"]
        .as_array()
        .expect("test_seeds is an array")
        .iter()
        .map(|s| {
            s.as_u64()
                .and_then(|s| u32::try_from(s).ok())
                .expect("a u32 seed")
        })
        .collect();
    assert_eq!(seeds.len(), 2, "{name}: test_seeds must hold two seeds");
    // Older entries predate these fields: the diffuse override, compensation on.
    let material_override = match &entry["material_override"] {
        Value::Null if entry.get("material_override").is_some() => MaterialOverride::None,
        Value::Null | Value::String(_) => MaterialOverride::Diffuse,
        other => panic!("{name}: material_override must be null or a string, got {other}"),
    };
    let energy_compensation = entry["energy_compensation"].as_bool().unwrap_or(true);
    let env = env_of(name, entry);
    seeds
        .iter()
        .map(|&seed| RenderOptions {
            width: as_u32(entry, "width"),
            height: as_u32(entry, "height"),
            spp,
            seed,
            max_bounces: as_u32(entry, "max_bounces"),
            filter: FilterKind::Box,
            env: aperture_shading::Environment::Constant(env),
            material_override,
            energy_compensation,
            ..RenderOptions::default()
        })
        .collect()
}

/// Our two renders of the scene `gltf`, one per seed.
fn render_ours(name: &str, entry: &Value, gltf: &Path) -> Vec<Image> {
    let scene = aperture_scene::load(gltf, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    // The aperture comes from the camera's extras; make sure it reached the camera.
    let radius = scene.cameras[0].dof.effective_radius();
    let want_radius = as_f64(entry, "aperture_radius") as f32;
    assert!(
        (radius - want_radius).abs() <= 1e-6,
        "{name}: camera aperture radius {radius}, manifest says {want_radius}"
    );
    let accel = build_accel(&scene, Default::default());
    render_options(name, entry)
        .iter()
        .map(|opts| {
            let film =
                render(&scene, &accel, opts, &|_, _| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(film.dropped_samples(), 0, "{name}: dropped samples");
            image_of(opts.width, opts.height, film.to_rgba())
        })
        .collect()
}

fn measure(name: &str) -> Agreement {
    let entry = manifest_entry(name);
    let dir = reference_dir();
    let gltf = dir.join(entry["gltf"].as_str().expect("gltf is a string"));
    let exr = dir.join(entry["exr"].as_str().expect("exr is a string"));
    let (width, height) = (as_u32(&entry, "width"), as_u32(&entry, "height"));

    let reference = read_exr(&exr).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!((reference.width, reference.height), (width, height));
    let renders = render_ours(name, &entry, &gltf);
    compare(
        name,
        &renders[0],
        &renders[1],
        &reference,
        as_f64(&entry, "reference_noise_rmse"),
    )
}

/// Our renders `a` and `b` (and their average, written for a look) against the reference.
fn compare(name: &str, a: &Image, b: &Image, reference: &Image, noise_ref: f64) -> Agreement {
    let (width, height) = (reference.width, reference.height);
    let average = image_of(
        width,
        height,
        a.rgba
            .iter()
            .zip(&b.rgba)
            .map(|(p, q)| std::array::from_fn(|c| 0.5 * (p[c] + q[c])))
            .collect(),
    );
    // For a look when a scene disagrees: target/tmp/reference_mitsuba/<name>.exr.
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("reference_mitsuba");
    std::fs::create_dir_all(&out).expect("creating the output folder");
    aperture_imageio::write_exr(&out.join(format!("{name}.exr")), &average)
        .unwrap_or_else(|e| panic!("{name}: {e}"));

    let full = Comparison::new(a, b, &average, reference, noise_ref);
    // Mitsuba's independent sampler makes its pixel errors independent, so a k×k block mean
    // carries exactly 1/k of the per-pixel noise RMSE; ours is measured, as at full size.
    let ds = |im: &Image| downsample(im, BLOCK);
    let block = Comparison::new(
        &ds(a),
        &ds(b),
        &ds(&average),
        &ds(reference),
        noise_ref / f64::from(BLOCK),
    );
    let ours = metrics::mean_rgb(&average).expect("finite");
    let theirs = metrics::mean_rgb(reference).expect("finite");
    let ratios = std::array::from_fn(|c| ours[c] / theirs[c]);
    // The scenes are asymmetric: against the left-right mirrored reference the error must be far
    // above the noise, so a mirrored camera frame (Mitsuba's +X points left) cannot pass.
    let mirrored = image_of(
        width,
        height,
        reference
            .rgba
            .chunks(width as usize)
            .flat_map(|row| row.iter().rev().copied())
            .collect(),
    );
    let rmse_mirrored = metrics::rmse(&average, &mirrored).expect("same size");
    println!(
        "{name}: pixels: {}\n{name}: {BLOCK}x{BLOCK} blocks: {}\n{name}: mean ours \
         {ours:.5?}, reference {theirs:.5?}, ratio {ratios:.5?}; rmse against the mirrored \
         reference {rmse_mirrored:.5}",
        full.report(),
        block.report(),
    );
    Agreement {
        full,
        block,
        rmse_mirrored,
        ratios,
    }
}

fn check(name: &str) {
    let m = measure(name);
    assert!(
        m.rmse_mirrored > 4.0 * RMSE_FACTOR * m.full.expected(),
        "{name}: the scene is too symmetric to detect a mirrored image ({:.5} vs noise {:.5})",
        m.rmse_mirrored,
        m.full.expected()
    );
    assert!(
        m.full.passes(),
        "{name}: pixels disagree with Mitsuba beyond noise: {}",
        m.full.report()
    );
    assert!(
        m.block.passes(),
        "{name}: {BLOCK}x{BLOCK} block means disagree with Mitsuba beyond noise: {}",
        m.block.report()
    );
    for (c, r) in ["R", "G", "B"].iter().zip(m.ratios) {
        assert!(
            (r - 1.0).abs() <= MEAN_TOLERANCE,
            "{name}: mean {c} is {r:.5} × Mitsuba's (tolerance ±{MEAN_TOLERANCE})"
        );
    }
}

#[test]
fn dof_point_light_agrees_with_mitsuba() {
    check("dof_point");
}

#[test]
fn pinhole_point_light_agrees_with_mitsuba() {
    check("pinhole_point");
}

#[test]
fn dof_emissive_quad_agrees_with_mitsuba() {
    check("dof_area");
}

#[test]
fn dof_environment_agrees_with_mitsuba() {
    check("dof_env");
}

#[test]
fn smooth_glass_sphere_agrees_with_mitsuba() {
    check("glass_smooth");
}

#[test]
fn rough_glass_sphere_agrees_with_mitsuba() {
    check("glass_rough");
}

#[test]
fn absorbing_glass_block_agrees_with_mitsuba() {
    check("glass_absorbing");
}
