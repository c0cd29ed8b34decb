//! Analytic accuracy checks (issue 6): renders and camera geometry against closed forms and an
//! independent numerical quadrature, each written here from the textbook formulas rather than
//! taken from the renderer.
//!
//! - GGX white furnace: a sphere in a uniform environment, binned by view cosine, against the
//!   directional albedo E(μo) integrated numerically.
//! - An emissive rectangle over a diffuse plane against the closed-form form factor.
//! - A spot light's cone falloff (KHR_lights_punctual) over the whole cone, and a directional
//!   light at oblique incidence.
//! - The circle of confusion over a grid of focus, depth, radius, blades and squeeze, solved
//!   exactly through the `Camera` API (no rendering).

use aperture_render::{
    test_scenes, Aperture, Camera, CameraModel, CameraSample, Environment, FilterKind,
    MaterialOverride, RenderOptions,
};
use aperture_scene::{Dof, Light, LightKind, Material, Scene};
use glam::{Affine3A, DVec2, DVec3, Vec2, Vec3, Vec4};
use std::f64::consts::PI;

use aperture_tests::render_checked;

fn opts(size: u32, spp: u32, max_bounces: u32) -> RenderOptions {
    RenderOptions {
        width: size,
        height: size,
        spp,
        seed: 11,
        max_bounces,
        filter: FilterKind::Box,
        ..RenderOptions::default()
    }
}

/// Pinhole rays through a `k × k` grid of positions inside pixel `(x, y)`: with the box filter
/// a pixel is the mean over its area, so predictions are averaged over the same area.
fn subpixel_rays(cam: &Camera, x: u32, y: u32, k: u32) -> Vec<(DVec3, DVec3)> {
    (0..k * k)
        .map(|i| {
            let p_film = Vec2::new(
                x as f32 + ((i % k) as f32 + 0.5) / k as f32,
                y as f32 + ((i / k) as f32 + 0.5) / k as f32,
            );
            let r = cam
                .generate_ray(&CameraSample {
                    p_film,
                    p_lens: Vec2::ZERO,
                })
                .expect("pinhole ray");
            (r.origin.as_dvec3(), r.dir.as_dvec3())
        })
        .collect()
}

/// Where a ray meets the plane y = 0, if in front of it.
fn hit_ground(o: DVec3, d: DVec3) -> Option<DVec3> {
    let t = -o.y / d.y;
    (t > 0.0).then(|| o + t * d)
}

// ---------------------------------------------------------------------------------------------
// 1. GGX white furnace
// ---------------------------------------------------------------------------------------------

/// Schlick's Fresnel.
fn schlick(f0: f64, c: f64) -> f64 {
    f0 + (1.0 - f0) * (1.0 - c).clamp(0.0, 1.0).powi(5)
}

/// Smith's Λ for GGX in terms of the tangent of the polar angle (Heitz 2014, "Understanding
/// the masking-shadowing function").
fn smith_lambda(alpha: f64, cos: f64) -> f64 {
    let tan2 = (1.0 - cos * cos).max(0.0) / (cos * cos);
    0.5 * (-1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// Directional albedo E(μo) = ∫ f(ωo, ωi) cos θi dωi of the glTF BSDF with a white base
/// (glTF 2.0 Appendix B), by midpoint quadrature in f64.
///
/// The renderer's `smith_v` is the *height-correlated* Smith visibility, so the reference uses
/// the height-correlated masking-shadowing G2 = 1 / (1 + Λ(ωo) + Λ(ωi)) (Heitz 2014),
/// written with Λ instead of the renderer's algebraic form. The specular part is integrated
/// over half-vectors in the variables (u, φ) in which D(h) cos θh dωh = du dφ / 2π, i.e.
/// tan² θh = α² u / (1 − u) (Walter et al. 2007, the GGX sampling formula): with
/// f cos θi dωi = F D G2 (ωo·h) / μo dωh the integrand F G2 (ωo·h) / (μo cos θh) is
/// smooth, so even α = 0.0025 needs no special care. The Lambertian part of a dielectric,
/// (1 − F(ωo·h)) / π, is integrated with cosine-weighted (u, φ).
///
/// `metallic` 1 means F = 1 (base colour 1); `metallic` 0 is the glTF dielectric with F0 = 0.04
/// and base colour 1. φ runs over [0, π] only: the integrand is symmetric in φ.
fn directional_albedo(mu_o: f64, alpha: f64, metallic: bool) -> f64 {
    const NU: usize = 192;
    const NPHI: usize = 64;
    let f0 = if metallic { 1.0 } else { 0.04 };
    let wo = DVec3::new((1.0 - mu_o * mu_o).max(0.0).sqrt(), 0.0, mu_o);
    let mut spec = 0.0;
    let mut diffuse = 0.0;
    for i in 0..NU {
        let u = (i as f64 + 0.5) / NU as f64;
        let tan_h = alpha * (u / (1.0 - u)).sqrt();
        let cos_h = 1.0 / (1.0 + tan_h * tan_h).sqrt();
        let sin_h = tan_h * cos_h;
        for j in 0..NPHI {
            let phi = PI * (j as f64 + 0.5) / NPHI as f64;
            let h = DVec3::new(sin_h * phi.cos(), sin_h * phi.sin(), cos_h);
            let oh = wo.dot(h);
            let wi = 2.0 * oh * h - wo;
            if oh > 0.0 && wi.z > 0.0 {
                let g2 = 1.0 / (1.0 + smith_lambda(alpha, mu_o) + smith_lambda(alpha, wi.z));
                spec += schlick(f0, oh) * g2 * oh / (mu_o * cos_h);
            }
            if !metallic {
                // Cosine-weighted ωi: the Lambertian lobe's density is cos θi / π.
                let r = u.sqrt();
                let wi = DVec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u).sqrt());
                let h = (wo + wi).normalize();
                diffuse += 1.0 - schlick(f0, wo.dot(h));
            }
        }
    }
    (spec + diffuse) / (NU * NPHI) as f64
}

/// E(μ) tabulated on a fine μ grid, linearly interpolated (E is smooth in μ).
struct AlbedoTable {
    lo: f64,
    values: Vec<f64>,
}

impl AlbedoTable {
    const STEPS: usize = 100;

    fn new(lo: f64, f: impl Fn(f64) -> f64) -> Self {
        let values = (0..=Self::STEPS)
            .map(|i| f(lo + (1.0 - lo) * i as f64 / Self::STEPS as f64))
            .collect();
        Self { lo, values }
    }

    fn at(&self, mu: f64) -> f64 {
        let x = ((mu - self.lo) / (1.0 - self.lo) * Self::STEPS as f64).max(0.0);
        let i = (x as usize).min(Self::STEPS - 1);
        let t = (x - i as f64).min(1.0);
        self.values[i] * (1.0 - t) + self.values[i + 1] * t
    }
}

/// A sphere of radius 1 (icosphere, 5120 triangles) in front of a pinhole camera at distance 3.
fn furnace_scene(material: Material) -> Scene {
    let cam =
        test_scenes::look_at_camera(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 0.8, Dof::default());
    test_scenes::scene(
        vec![(test_scenes::icosphere(4, 0), Affine3A::IDENTITY)],
        vec![material],
        cam,
    )
}

/// Smallest view cosine binned: below it the renderer bends shading normals towards the viewer
/// (integrator's `MIN_VIEW_COS`) and the faceted silhouette departs from the sphere.
const FURNACE_MU_MIN: f64 = 0.2;
const FURNACE_BINS: usize = 8;

struct FurnaceResult {
    /// Per bin: (rendered mean, reference mean, pixels).
    bins: Vec<(f64, f64, usize)>,
    /// The brightest sphere pixel.
    max_pixel: f64,
}

/// Renders the furnace and bins sphere pixels by their view cosine, computed for the exact
/// sphere through the camera (4 × 4 positions per pixel).
fn furnace(
    material: Material,
    material_override: MaterialOverride,
    e: &AlbedoTable,
) -> FurnaceResult {
    let scene = furnace_scene(material);
    let size = 64;
    let o = RenderOptions {
        env: Environment::Constant(Vec3::ONE),
        material_override,
        // The quadrature is of glTF's single-scattering lobes: compare them as they are.
        // (`energy_furnace.rs` checks the compensated lobes, the default.)
        energy_compensation: false,
        ..opts(size, 64, 4)
    };
    let film = render_checked(&scene, &o);
    let cam = Camera::new(&scene.cameras[0], size, size);
    let mut bins = vec![(0.0, 0.0, 0usize); FURNACE_BINS];
    let mut max_pixel = 0.0f64;
    for y in 0..size {
        for x in 0..size {
            let px = film.pixel(x, y);
            // Only pixels the mesh covers entirely.
            if px[3] != 1.0 {
                continue;
            }
            max_pixel = max_pixel.max(px[0] as f64);
            let mut mus = Vec::new();
            for (o, d) in subpixel_rays(&cam, x, y, 4) {
                // Unit sphere at the origin: |o + t d|² = 1.
                let b = o.dot(d);
                let disc = b * b - (o.length_squared() - 1.0);
                if disc < 0.0 {
                    break;
                }
                let p = o + (-b - disc.sqrt()) * d;
                mus.push(p.normalize().dot(-d));
            }
            if mus.len() != 16 || mus.iter().any(|&m| m < FURNACE_MU_MIN) {
                continue;
            }
            let mu = mus.iter().sum::<f64>() / 16.0;
            let want = mus.iter().map(|&m| e.at(m)).sum::<f64>() / 16.0;
            let bin = (((mu - FURNACE_MU_MIN) / (1.0 - FURNACE_MU_MIN) * FURNACE_BINS as f64)
                as usize)
                .min(FURNACE_BINS - 1);
            bins[bin].0 += px[0] as f64;
            bins[bin].1 += want;
            bins[bin].2 += 1;
        }
    }
    for b in &mut bins {
        b.0 /= b.2 as f64;
        b.1 /= b.2 as f64;
    }
    FurnaceResult { bins, max_pixel }
}

/// A white GGX conductor (F = 1) at five roughnesses, a white glTF dielectric, and the Lambert
/// clay in a furnace of radiance 1: every view-cosine bin matches the quadrature of E(μo), and
/// the conductors and the clay never create energy. Rendered without energy compensation
/// (`--no-energy-compensation`): this pins glTF's single-scattering formulas, which the
/// compensated default deliberately departs from (issue 14; `energy_furnace.rs`). On a convex sphere only the first bounce
/// reaches the environment (a reflected ray leaves above the facet's plane and cannot meet the
/// sphere again), so the image is E(μo) itself.
#[test]
fn ggx_white_furnace_matches_directional_albedo_quadrature() {
    // Tolerances.
    // - Bin means: each bin holds ≥ 40 pixels × 64 samples; the conductor's per-sample weight
    //   G2/G1 lies in [0, 1] and the dielectric's in about [0, 2], so the noise of a bin mean is
    //   a few 1e-3 at most. The faceted mesh (5120 triangles) departs from the sphere by < 1e-3
    //   in position and a few 1e-3 in the view cosine, and rays between the shading and the
    //   geometric horizon are lost (only for the roughest lobes). Measured worst: 0.0035
    //   (roughness 1, μo 0.2–0.3; 0.0022 with 4× the triangles, 0.0014 with another seed).
    const BIN_TOL: f64 = 0.01;
    // - Energy of a conductor: float rounding only (see below).
    const PIXEL_TOL: f64 = 1e-4;
    enum Kind {
        Conductor,
        GltfDielectric,
        Lambert,
    }
    let mut cases: Vec<(String, Material, MaterialOverride, AlbedoTable, Kind)> = Vec::new();
    for roughness in [0.05, 0.25, 0.5, 0.75, 1.0] {
        let alpha = roughness * roughness;
        cases.push((
            format!("conductor r={roughness}"),
            Material {
                base_color_factor: Vec4::ONE,
                metallic_factor: 1.0,
                roughness_factor: roughness as f32,
                ..Material::default()
            },
            MaterialOverride::None,
            AlbedoTable::new(FURNACE_MU_MIN, |mu| directional_albedo(mu, alpha, true)),
            Kind::Conductor,
        ));
    }
    cases.push((
        "dielectric r=0.5".into(),
        Material {
            roughness_factor: 0.5,
            ..test_scenes::matte(Vec3::ONE)
        },
        MaterialOverride::None,
        AlbedoTable::new(FURNACE_MU_MIN, |mu| directional_albedo(mu, 0.25, false)),
        Kind::GltfDielectric,
    ));
    cases.push((
        "Lambert (clay)".into(),
        test_scenes::matte(Vec3::ONE),
        MaterialOverride::Diffuse,
        AlbedoTable::new(FURNACE_MU_MIN, |_| 1.0),
        Kind::Lambert,
    ));
    let mut worst_all = 0.0f64;
    for (name, material, ov, table, kind) in cases {
        let r = furnace(material, ov, &table);
        let mut worst = 0.0f64;
        let mut line = String::new();
        for &(got, want, n) in &r.bins {
            assert!(n >= 40, "{name}: only {n} pixels in a bin");
            worst = worst.max((got - want).abs());
            line += &format!(" {got:.4}/{want:.4}");
        }
        println!(
            "furnace {name:<18} worst |bin − E| {worst:.4}, max pixel {:.5}; \
             rendered/E per bin (μ {FURNACE_MU_MIN}..1):{line}",
            r.max_pixel
        );
        assert!(worst < BIN_TOL, "{name}: {worst}");
        match kind {
            // Every sample weighs G2/G1 ≤ 1: no pixel may exceed 1 beyond float rounding.
            Kind::Conductor => {
                assert!(r.max_pixel <= 1.0 + PIXEL_TOL, "{name}: {}", r.max_pixel)
            }
            // Diffuse = 1 within 0.5% in every bin (issue 6; measured 4e-4: the clay's
            // per-sample weight is exactly 1, so only rounding and faceting remain).
            Kind::Lambert => {
                for &(got, _, _) in &r.bins {
                    assert!((got - 1.0).abs() < 0.005, "{name}: {got}");
                }
            }
            // glTF's dielectric (Appendix B's fresnel_mix with F(ωo·h) per direction pair) is
            // not energy-conserving at grazing view: its own E(μo) exceeds 1 (1.074 at μo 0.2).
            // Without energy compensation the renderer reproduces that excess (the bin
            // comparison above); with it (the default, issue 14) the diffuse base is weighted
            // by what the specular layer leaves at the view and the excess is gone
            // (`energy_furnace.rs`). Pin the reference's excess so a change of model is
            // noticed here.
            Kind::GltfDielectric => {
                let e = table.at(FURNACE_MU_MIN);
                assert!(
                    (1.05..1.1).contains(&e),
                    "{name}: E({FURNACE_MU_MIN}) = {e}"
                );
            }
        }
        worst_all = worst_all.max(worst);
    }
    println!("furnace: worst bin error over all materials {worst_all:.4} (tolerance {BIN_TOL})");
}

/// The quadrature itself against closed forms and a brute-force sum, so a wrong reference
/// cannot make the furnace test pass or fail by accident.
#[test]
fn albedo_quadrature_reproduces_known_limits() {
    // A near-mirror conductor with F = 1 reflects everything (G2 → 1 as α → 0).
    let e = directional_albedo(0.7, 1e-4, true);
    assert!((e - 1.0).abs() < 1e-4, "{e}");
    // GGX with α = 1 has D = 1/π and, at normal view, G2 = 2μi / (1 + μi), so
    // E(1) = ∫₀¹ μi / (1 + μi) dμi = 1 − ln 2.
    let e = directional_albedo(1.0, 1.0, true);
    println!(
        "quadrature check: α 1, μo 1: {e:.6} vs 1 − ln 2 = {:.6}",
        1.0 - 2f64.ln()
    );
    assert!((e - (1.0 - 2f64.ln())).abs() < 1e-4, "{e}");
    // A different parametrisation must agree: a brute-force sum over ωi on a uniform (μ, φ)
    // grid, with the textbook D (Walter et al. 2007) written out.
    let (alpha, mu_o) = (0.5f64, 0.6f64);
    let wo = DVec3::new((1.0 - mu_o * mu_o).sqrt(), 0.0, mu_o);
    let n = 1200;
    let mut sum = 0.0;
    for i in 0..n {
        let mu_i = (i as f64 + 0.5) / n as f64;
        for j in 0..n {
            let phi = 2.0 * PI * (j as f64 + 0.5) / n as f64;
            let s = (1.0 - mu_i * mu_i).sqrt();
            let wi = DVec3::new(s * phi.cos(), s * phi.sin(), mu_i);
            let h = (wo + wi).normalize();
            let c2 = h.z * h.z;
            let tan2 = (1.0 - c2) / c2;
            let d = alpha * alpha / (PI * c2 * c2 * (alpha * alpha + tan2).powi(2));
            let g2 = 1.0 / (1.0 + smith_lambda(alpha, mu_o) + smith_lambda(alpha, mu_i));
            sum += d * g2 / (4.0 * mu_o * mu_i) * mu_i;
        }
    }
    let brute = sum * 2.0 * PI / (n * n) as f64;
    let e = directional_albedo(mu_o, alpha, true);
    println!("quadrature check: α 0.5, μo 0.6: {e:.5} vs brute force {brute:.5}");
    assert!((e - brute).abs() < 1e-3, "{e} vs {brute}");
}

// ---------------------------------------------------------------------------------------------
// 2. Emissive rectangle over a diffuse plane
// ---------------------------------------------------------------------------------------------

/// Form factor from a differential area to a parallel rectangle `[0, a] × [0, b]` at height
/// `h` with one corner straight above it (Howell's catalogue of configuration factors, B-3):
/// F = 1/2π [X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))], X = a/h, Y = b/h.
/// Signed in `a` and `b`, so rectangles not above the point are sums and differences of four.
fn corner_form_factor(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a.abs() / h, b.abs() / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    a.signum() * b.signum() * (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
}

/// Form factor from a differential area at `(px, 0, pz)` facing +Y to the rectangle
/// `[x0, x1] × [z0, z1]` at height `h` (superposition of four corner rectangles).
fn rect_form_factor(px: f64, pz: f64, [x0, x1, z0, z1]: [f64; 4], h: f64) -> f64 {
    let g = |x: f64, z: f64| corner_form_factor(x - px, z - pz, h);
    g(x1, z1) - g(x0, z1) - g(x1, z0) + g(x0, z0)
}

/// A 40 × 40 diffuse plane (albedo 0.8) at y = 0 under an emissive 1.2 × 0.8 rectangle of
/// radiance `L` at height `h`, facing down (it emits on both sides; only one faces the plane).
/// With `max_bounces` 0 only direct light counts, so the plane's radiance is
/// albedo/π · E = albedo · L · F, F the form factor above. Probes: every pixel whose area
/// sees only the plane (the emitter hides part of it).
#[test]
fn emissive_rectangle_over_a_plane_matches_the_form_factor() {
    let (albedo, radiance, h) = (0.8f64, 3.0f32, 0.7f64);
    let rect = [-0.6, 0.6, -0.4, 0.4];
    let cam = test_scenes::look_at_camera(
        Vec3::new(0.0, 3.5, 4.0),
        Vec3::new(0.0, 0.0, 0.3),
        0.9,
        Dof::default(),
    );
    let scene = test_scenes::scene(
        vec![
            (test_scenes::quad(40.0, 0), Affine3A::IDENTITY),
            (
                test_scenes::quad(1.0, 1),
                Affine3A::from_translation(Vec3::new(0.0, h as f32, 0.0))
                    * Affine3A::from_scale(Vec3::new(1.2, 1.0, 0.8)),
            ),
        ],
        vec![
            test_scenes::matte(Vec3::splat(albedo as f32)),
            test_scenes::emitter(Vec3::splat(radiance)),
        ],
        cam,
    );
    let size = 32;
    let o = RenderOptions {
        material_override: MaterialOverride::Diffuse,
        ..opts(size, 256, 0)
    };
    let film = render_checked(&scene, &o);
    let cam = Camera::new(&scene.cameras[0], size, size);
    // The prediction per pixel; `None` where part of the pixel shows the emitter or no plane.
    let predict = |x: u32, y: u32| -> Option<f64> {
        let rays = subpixel_rays(&cam, x, y, 4);
        let mut want = 0.0;
        for &(o, d) in &rays {
            let t = (h - o.y) / d.y;
            let e = o + t * d;
            let (ex, ez) = (rect[0]..=rect[1], rect[2]..=rect[3]);
            if t > 0.0 && ex.contains(&e.x) && ez.contains(&e.z) {
                return None;
            }
            let q = hit_ground(o, d)?;
            if q.x.abs() >= 20.0 || q.z.abs() >= 20.0 {
                return None;
            }
            want += albedo * radiance as f64 * rect_form_factor(q.x, q.z, rect, h);
        }
        Some(want / rays.len() as f64)
    };
    let predicted: Vec<Option<f64>> = (0..size * size)
        .map(|i| predict(i % size, i / size))
        .collect();
    let (mut sum_got, mut sum_want) = (0.0f64, 0.0f64);
    let (mut worst, mut sq) = (0.0f64, 0.0f64);
    let mut n = 0usize;
    let mut peak = 0.0f64;
    for y in 0..size {
        for x in 0..size {
            // Sub-pixel positions can miss a sliver of the emitter's silhouette: a probe's
            // neighbours must see only the plane too.
            let clear = (y.saturating_sub(1)..(y + 2).min(size)).all(|ny| {
                (x.saturating_sub(1)..(x + 2).min(size))
                    .all(|nx| predicted[(ny * size + nx) as usize].is_some())
            });
            let Some(want) = predicted[(y * size + x) as usize].filter(|_| clear) else {
                continue;
            };
            let got = film.pixel(x, y)[0] as f64;
            let rel = (got - want) / want;
            worst = worst.max(rel.abs());
            sq += rel * rel;
            sum_got += got;
            sum_want += want;
            peak = peak.max(want);
            n += 1;
        }
    }
    let bias = sum_got / sum_want - 1.0;
    let rms = (sq / n as f64).sqrt();
    println!(
        "emissive rectangle: {n} probe pixels (peak {peak:.4}), mean ratio − 1 = {bias:+.5}, \
         per-pixel relative error rms {rms:.4}, worst {worst:.4}"
    );
    assert!(n > 500, "{n}");
    // Tolerances. The mean over all probes averages ~250 000 samples: its noise is well below
    // 0.1%, so 0.3% bounds a bias. Per pixel, 256 light samples (MIS with BSDF samples) leave
    // ~0.4% rms noise (measured), 2% in the worst of ~950 pixels.
    assert!(bias.abs() < 0.003, "{bias}");
    assert!(worst < 0.05, "{worst}");
}

// ---------------------------------------------------------------------------------------------
// 3. Spot cone falloff and an oblique directional light
// ---------------------------------------------------------------------------------------------

/// A spot light straight above a diffuse plane, over its whole cone: inside the inner cone,
/// through the smooth falloff (KHR_lights_punctual: `a = saturate((cos θ − cos outer) /
/// (cos inner − cos outer))`, intensity × a²), at the edge and beyond it, against
/// L = albedo/π · I cos θ / r² · a². Then a directional light at 36.9° from the normal:
/// L = albedo/π · E cos θ everywhere. (`render_integrator.rs` checks the point light's inverse
/// square and the directional light at normal incidence.)
#[test]
fn spot_cone_falloff_and_oblique_directional_light() {
    let (albedo, intensity) = (0.8f64, 5.0f64);
    let (inner, outer) = (0.3f64, 0.5f64);
    let light_pos = DVec3::new(0.0, 2.0, 0.0);
    let mut scene = test_scenes::lit_plane(1.0);
    scene.cameras[0] = test_scenes::look_at_camera(
        Vec3::new(0.0, 4.0, 3.0),
        Vec3::new(0.0, 0.0, 0.2),
        0.7,
        Dof::default(),
    );
    scene.lights[0] = Light {
        name: None,
        kind: LightKind::Spot {
            inner_cone: inner as f32,
            outer_cone: outer as f32,
        },
        position: light_pos.as_vec3(),
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(intensity as f32),
    };
    let size = 48;
    let o = RenderOptions {
        material_override: MaterialOverride::Diffuse,
        ..opts(size, 64, 0)
    };
    let film = render_checked(&scene, &o);
    let cam = Camera::new(&scene.cameras[0], size, size);
    let radiance = |q: DVec3| -> (f64, f64) {
        let d = light_pos - q;
        let r = d.length();
        // Angle between the spot's axis (−Y) and the direction from the light to q.
        let angle = (d.y / r).acos();
        let a = ((angle.cos() - outer.cos()) / (inner.cos() - outer.cos())).clamp(0.0, 1.0);
        (albedo / PI * intensity * (d.y / r) / (r * r) * a * a, angle)
    };
    let peak = albedo / PI * intensity / (light_pos.y * light_pos.y);
    // Worst |error| / peak in: the inner cone, the falloff band, pixels that straddle a cone
    // edge; and the count of dark pixels (wholly outside the outer cone) that are not exactly 0.
    let (mut core, mut band, mut edge) = (0.0f64, 0.0f64, 0.0f64);
    let (mut n_core, mut n_band, mut n_edge, mut n_dark) = (0, 0, 0, 0);
    for y in 0..size {
        for x in 0..size {
            let got = film.pixel(x, y)[0] as f64;
            let rays = subpixel_rays(&cam, x, y, 8);
            let (mut want, mut lo, mut hi) = (0.0, f64::MAX, f64::MIN);
            for &(o, d) in &rays {
                let q = hit_ground(o, d).expect("the camera sees only the plane");
                let (l, angle) = radiance(q);
                want += l;
                lo = lo.min(angle);
                hi = hi.max(angle);
            }
            want /= rays.len() as f64;
            let err = (got - want).abs() / peak;
            // Sub-pixel positions are 1/8 px apart; a pixel's own angles extend ~1/16 px
            // beyond them, far less than 0.01 rad here.
            if lo > outer + 0.01 {
                assert_eq!(got, 0.0, "pixel ({x}, {y}) outside the outer cone");
                n_dark += 1;
            } else if hi < inner - 0.01 {
                core = core.max(err);
                n_core += 1;
            } else if lo > inner + 0.01 && hi < outer - 0.01 {
                band = band.max(err);
                n_band += 1;
            } else {
                edge = edge.max(err);
                n_edge += 1;
            }
        }
    }
    println!(
        "spot: worst |error| / peak: inner cone {core:.2e} ({n_core} px), falloff {band:.2e} \
         ({n_band} px), straddling an edge {edge:.2e} ({n_edge} px); {n_dark} px outside, all 0"
    );
    assert!(n_core > 50 && n_band > 50 && n_edge > 20 && n_dark > 100);
    // Tolerances. A spot light is a delta: each sample's value is exact, so the only error is
    // integrating the pixel with 64 stratified positions where the prediction uses an 8 × 8
    // grid. Where the radiance is smooth that is ≲ 1e-3 of the peak (measured: 5e-5 inside
    // the inner cone, 3e-4 in the falloff); a pixel straddling a cone edge has a kink of a²
    // (inner edge) inside it, which both quadratures resolve less well (measured: 1e-3).
    assert!(core < 2e-3 && band < 2e-3, "{core} {band}");
    assert!(edge < 5e-3, "{edge}");

    // Directional, 36.9° from the normal: cos θ = 0.8.
    let irradiance = 2.0f64;
    scene.lights[0] = Light {
        name: None,
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        direction: Vec3::new(0.6, -0.8, 0.0),
        intensity: Vec3::splat(irradiance as f32),
    };
    let film = render_checked(&scene, &o);
    let want = albedo / PI * irradiance * 0.8;
    let worst = film
        .to_rgba()
        .iter()
        .map(|p| (p[0] as f64 - want).abs() / want)
        .fold(0.0, f64::max);
    println!("directional at cos θ 0.8: worst relative error {worst:.2e}");
    // Every sample is exact up to f32 rounding.
    assert!(worst < 1e-5, "{worst}");
}

// ---------------------------------------------------------------------------------------------
// 4. Circle of confusion, through the camera API
// ---------------------------------------------------------------------------------------------

/// Image size for the CoC grid: no image is rendered, only film positions are solved for, so a
/// large film keeps even the smallest blur figure many f32 ulps wide.
const COC_W: u32 = 1500;
const COC_H: u32 = 1000;
/// Lens samples per axis of the interior grid.
const COC_LENS: u32 = 32;
/// Lens samples along each dense line.
const COC_LINE: u32 = 1024;

/// Lens samples in `[0, 1)²`: a `COC_LENS²` grid of cell centres for the interior, and dense
/// lines along the unit square's four edges and its horizontal midline. Without knowing how
/// the camera maps the square onto the aperture, dense lines are what reach its boundary
/// (the disc's boundary is the square's edge; a polygon's corners and edges lie at the ends
/// of its wedges, along u.x) so the figure's extent and area can be measured tightly.
fn coc_lens_samples() -> Vec<Vec2> {
    let top = 1.0 - f32::EPSILON;
    let mut v: Vec<Vec2> = (0..COC_LENS * COC_LENS)
        .map(|i| {
            Vec2::new(
                ((i % COC_LENS) as f32 + 0.5) / COC_LENS as f32,
                ((i / COC_LENS) as f32 + 0.5) / COC_LENS as f32,
            )
        })
        .collect();
    for i in 0..COC_LINE {
        let t = (i as f32 + 0.5) / COC_LINE as f32;
        for e in [0.0, 0.5, top] {
            v.push(Vec2::new(t, e));
        }
        for e in [0.0, top] {
            v.push(Vec2::new(e, t));
        }
    }
    v
}

/// Convex hull area (Andrew's monotone chain), shoelace formula.
fn hull_area(points: &[DVec2]) -> f64 {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<DVec2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    let n = hull.len();
    (0..n)
        .map(|i| hull[i].perp_dot(hull[(i + 1) % n]))
        .sum::<f64>()
        .abs()
        * 0.5
}

/// One point of the CoC grid.
#[derive(Debug, Clone, Copy)]
struct CocCase {
    focus: f32,
    depth: f32,
    radius: f32,
    blades: u32,
    ratio: f32,
    rotation: f32,
}

/// What one grid point measured.
struct CocMeasure {
    /// SPEC §2's diameter, pixels.
    c_spec: f64,
    /// Largest |film offset − SPEC's offset for the sample's lens point|, pixels.
    offset_error: f64,
    /// Largest distance of a solved film point's ray from the world point, in pixels.
    residual: f64,
    /// Diameter of the circumscribed circle of the (unsqueezed) blur figure, pixels.
    diameter: f64,
    /// Largest excursion outside the predicted aperture shape, in units of c/2.
    outside: f64,
    /// Hull area of the blur figure over the predicted area.
    area_ratio: f64,
}

/// Solves, for every lens sample of a `COC_LENS²` grid, the film position whose ray passes
/// through a world point at depth `depth`, using only `Camera::generate_ray`. For a fixed lens
/// sample the ray's point at a given depth is affine in the film position (SPEC §2: the focus
/// point is linear in the pixel sample, the lens point fixed), so three rays determine the map
/// and a fourth checks that the solution really hits the point.
fn coc_measure(case: CocCase) -> CocMeasure {
    let dof = Dof {
        enabled: true,
        aperture_radius: case.radius,
        focus_distance: case.focus,
        blades: case.blades,
        rotation: case.rotation,
        ratio: case.ratio,
        ..Dof::default()
    };
    // A tilted camera away from the origin, so the world transform takes part.
    let sc = test_scenes::look_at_camera(
        Vec3::new(1.0, 2.0, 3.0),
        Vec3::new(0.4, 1.3, -2.0),
        0.8,
        dof,
    );
    let cam = Camera::new(&sc, COC_W, COC_H);
    let pinhole = Camera {
        aperture: Aperture::Pinhole,
        ..cam
    };
    let CameraModel::ThinLens { tan_half_y, .. } = cam.model else {
        unreachable!("perspective camera")
    };
    let camera_from_world = cam.world_from_camera.inverse();
    let z = case.depth as f64;
    // Off the optical axis: the focal "plane" is a plane, so the CoC does not depend on it.
    let p_cam = DVec3::new(0.15 * z, -0.1 * z, -z);
    let p_world = cam.world_from_camera.transform_point3(p_cam.as_vec3());
    let p_target = camera_from_world.transform_point3(p_world).as_dvec3();
    // Where a ray crosses the plane at depth z, in camera x, y.
    let at_depth = |c: &Camera, p_film: DVec2, p_lens: Vec2| -> (DVec2, DVec3) {
        let r = c
            .generate_ray(&CameraSample {
                p_film: p_film.as_vec2(),
                p_lens,
            })
            .expect("ray");
        let o = camera_from_world.transform_point3(r.origin).as_dvec3();
        let d = camera_from_world.transform_vector3(r.dir).as_dvec3();
        let t = (-z - o.z) / d.z;
        ((o + t * d).truncate(), o)
    };
    let solve = |c: &Camera, p_lens: Vec2| -> (DVec2, DVec3, f64) {
        let p0 = DVec2::new(COC_W as f64 * 0.5, COC_H as f64 * 0.5);
        let step = 100.0;
        let (x0, lens) = at_depth(c, p0, p_lens);
        let (xx, _) = at_depth(c, p0 + DVec2::X * step, p_lens);
        let (xy, _) = at_depth(c, p0 + DVec2::Y * step, p_lens);
        let j = glam::DMat2::from_cols((xx - x0) / step, (xy - x0) / step);
        let p = p0 + j.inverse() * (p_target.truncate() - x0);
        let (hit, _) = at_depth(c, p, p_lens);
        let residual = (j.inverse() * (hit - p_target.truncate())).length();
        (p, lens, residual)
    };
    let (p_pin, _, res_pin) = solve(&pinhole, Vec2::ZERO);
    let (f, r) = (case.focus as f64, case.radius as f64);
    let px_per_unit = COC_H as f64 / (2.0 * tan_half_y as f64);
    // SPEC §2.
    let c_spec = r * (1.0 / f - 1.0 / z).abs() * COC_H as f64 / tan_half_y as f64;
    // Film offset per unit of lens offset: behind the focal plane (z > f) the figure keeps the
    // aperture's orientation, in front of it it is point-reflected. Raster y points down.
    let k = (1.0 / f - 1.0 / z) * px_per_unit;
    // SPEC §2: corners on the unit circle at rotation + π/n + 2πk/n, counter-clockwise.
    let n_blades = case.blades as f64;
    let corners: Vec<DVec2> = (0..case.blades)
        .map(|i| {
            let a = case.rotation as f64 + PI / n_blades + 2.0 * PI * i as f64 / n_blades;
            DVec2::new(a.cos(), a.sin())
        })
        .collect();
    let mut m = CocMeasure {
        c_spec,
        offset_error: 0.0,
        residual: res_pin,
        diameter: 0.0,
        outside: 0.0,
        area_ratio: 0.0,
    };
    let lens_samples = coc_lens_samples();
    let mut film_points = Vec::with_capacity(lens_samples.len());
    for &p_lens in &lens_samples {
        let (p, lens, residual) = solve(&cam, p_lens);
        m.residual = m.residual.max(residual);
        let offset = p - p_pin;
        let want = DVec2::new(k * lens.x, -k * lens.y);
        m.offset_error = m.offset_error.max((offset - want).length());
        film_points.push(offset);
        // The figure in units of the CoC radius, unsqueezed and un-reflected: it must be the
        // unit aperture shape.
        let q = DVec2::new(offset.x * case.ratio as f64, -offset.y) * k.signum() / (0.5 * c_spec);
        m.diameter = m.diameter.max(q.length() * c_spec);
        let out = if corners.is_empty() {
            q.length() - 1.0
        } else {
            (0..corners.len())
                .map(|e| {
                    let (a, b) = (corners[e], corners[(e + 1) % corners.len()]);
                    // Signed distance outside edge a→b (counter-clockwise corners).
                    -(b - a).perp_dot(q - a) / (b - a).length()
                })
                .fold(f64::MIN, f64::max)
        };
        m.outside = m.outside.max(out);
    }
    let unit_area = if case.blades == 0 {
        PI
    } else {
        let n = case.blades as f64;
        0.5 * n * (2.0 * PI / n).sin()
    };
    let want_area = unit_area * (0.5 * c_spec).powi(2) / case.ratio as f64;
    m.area_ratio = hull_area(&film_points) / want_area;
    m
}

/// The blur figure of a point over a grid of focus distance (3), depth in front of and behind
/// the focal plane (4), aperture radius (2), blade count (disc, 3–8) and anamorphic ratio (3):
/// 504 cameras, 6144 lens samples each. For every lens sample the film offset from the pinhole
/// image is exactly SPEC §2's (−(1/z − 1/f) · H / (2 tan(yfov/2)) times the lens point, x
/// squeezed with the lens), so the figure is the aperture scaled to the CoC diameter: its
/// circumscribed diameter is `c_px`, it stays inside the predicted disc or regular polygon
/// (rotation, squeeze, point reflection in front of the focal plane included), and its area is
/// the polygon's `n/2 · sin(2π/n) · (c/2)² / ratio` (π (c/2)² / ratio for a disc).
#[test]
fn circle_of_confusion_grid_matches_spec_formula() {
    // Tolerances. Film positions are solved in f64 from f32 rays on a 1500 × 1000 film: the
    // rays' rounding (≈ 1e-7 relative) moves a solved film point by ≲ 1e-3 px near the centre
    // and by ~1e-5 of the offset for figures larger than the film (up to 1500 px here).
    const OFFSET_TOL_PX: f64 = 5e-3;
    const OFFSET_TOL_REL: f64 = 2e-5;
    // In units of the CoC radius: ≤ 5e-3 px over a radius ≥ 3 px.
    const OUTSIDE_TOL: f64 = 2e-3;
    // The dense lens lines (1024 samples) reach within about 1/1024 of the square's edge, so
    // the figure's outermost samples lie within ~n/2048 of the boundary in area (a polygon's
    // wedge depth is the square root of the fractional u.x) and the hull misses at most the
    // slivers between neighbouring samples: both well under 0.5% for n ≤ 8. Containment
    // (OUTSIDE_TOL) bounds both from above.
    const AREA_TOL: f64 = 0.005;
    const DIAMETER_TOL: f64 = 0.005;
    let mut n = 0;
    let (mut worst_offset, mut worst_residual, mut worst_outside) = (0.0f64, 0.0f64, f64::MIN);
    let mut worst_offset_rel = 0.0f64;
    let (mut min_area, mut max_area) = (f64::MAX, f64::MIN);
    let (mut min_diam, mut max_diam) = (f64::MAX, f64::MIN);
    let (mut min_c, mut max_c) = (f64::MAX, f64::MIN);
    for focus in [0.7f32, 2.0, 8.0] {
        for depth_factor in [0.4f32, 0.8, 1.3, 3.5] {
            for radius in [0.05f32, 0.3] {
                for blades in [0u32, 3, 4, 5, 6, 7, 8] {
                    for ratio in [1.0f32, 0.5, 2.0] {
                        let case = CocCase {
                            focus,
                            depth: focus * depth_factor,
                            radius,
                            blades,
                            ratio,
                            rotation: 0.37 * blades as f32,
                        };
                        let m = coc_measure(case);
                        let ctx = format!("{case:?}: c_spec {:.3} px", m.c_spec);
                        let tol = OFFSET_TOL_PX + OFFSET_TOL_REL * m.c_spec;
                        assert!(m.offset_error < tol, "{ctx}: offset {}", m.offset_error);
                        assert!(m.residual < tol, "{ctx}: residual {}", m.residual);
                        worst_offset_rel = worst_offset_rel.max(m.offset_error / m.c_spec);
                        assert!(m.outside < OUTSIDE_TOL, "{ctx}: outside {}", m.outside);
                        let d = m.diameter / m.c_spec;
                        assert!(
                            d > 1.0 - DIAMETER_TOL && d < 1.0 + OUTSIDE_TOL,
                            "{ctx}: diameter ratio {d}"
                        );
                        assert!(
                            m.area_ratio > 1.0 - AREA_TOL && m.area_ratio < 1.0 + 4.0 * OUTSIDE_TOL,
                            "{ctx}: area ratio {}",
                            m.area_ratio
                        );
                        worst_offset = worst_offset.max(m.offset_error);
                        worst_residual = worst_residual.max(m.residual);
                        worst_outside = worst_outside.max(m.outside);
                        min_area = min_area.min(m.area_ratio);
                        max_area = max_area.max(m.area_ratio);
                        min_diam = min_diam.min(d);
                        max_diam = max_diam.max(d);
                        min_c = min_c.min(m.c_spec);
                        max_c = max_c.max(m.c_spec);
                        n += 1;
                    }
                }
            }
        }
    }
    println!(
        "CoC grid: {n} cameras, c_spec {min_c:.2}..{max_c:.1} px; worst per-sample offset \
         error {worst_offset:.2e} px ({worst_offset_rel:.1e} of c), ray residual \
         {worst_residual:.2e} px, outside the shape {worst_outside:.2e} (c/2); diameter / c_spec \
         {min_diam:.4}..{max_diam:.4}, hull area / polygon area {min_area:.4}..{max_area:.4}"
    );
}
