//! GGX white furnace: a sphere in a uniform environment, binned by view cosine, against the
//! directional albedo E(μo) integrated numerically.

use aperture_render::{Camera, RenderOptions};
use aperture_scene::{Dof, Material, Scene};
use aperture_shading::{test_scenes, Environment, MaterialOverride};
use glam::{Affine3A, DVec3, Vec3, Vec4};
use std::f64::consts::PI;

use aperture_tests::render_checked;

use crate::{opts, subpixel_rays};

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

/// What a furnace material must satisfy beyond matching the quadrature.
enum Kind {
    Conductor,
    GltfDielectric,
    Lambert,
}

/// One furnace material: its name, the material and override, the reference E(μo), its kind.
type FurnaceCase = (String, Material, MaterialOverride, AlbedoTable, Kind);

/// A white conductor at five roughnesses, a white glTF dielectric and the Lambert clay.
fn furnace_cases() -> Vec<FurnaceCase> {
    let mut cases: Vec<FurnaceCase> = Vec::new();
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
    cases
}

/// Energy of a conductor: float rounding only (see [`check_kind`]).
const PIXEL_TOL: f64 = 1e-4;

/// What each kind of material must satisfy beyond matching the quadrature.
fn check_kind(name: &str, kind: Kind, r: &FurnaceResult, table: &AlbedoTable) {
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
    let mut worst_all = 0.0f64;
    for (name, material, ov, table, kind) in furnace_cases() {
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
        check_kind(&name, kind, &r, &table);
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
