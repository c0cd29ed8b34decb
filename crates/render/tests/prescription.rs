//! `lens_prescription` (issue 61) against first-order optics computed here independently of the
//! tracing code: the effective focal length and back focal distance of the ray-transfer (ABCD)
//! matrices, a focused point's spot, and the exit pupil's sampler against the naive one that
//! draws the whole rear element.

use aperture_render::camera::{Camera, CameraSample};
use aperture_render::realistic::{PupilSampling, RealisticLens};
use aperture_render::{Frame, RenderOptions};
use aperture_scene::{Dof, LensPrescription, LensSurface};
use aperture_shading::environment::Environment;
use aperture_shading::test_scenes;
use glam::{DVec2, DVec3, Vec2, Vec3};

/// The rows of a shipped lens file, parsed here (not by the scene crate).
fn rows(name: &str) -> Vec<[f64; 4]> {
    let path = format!("{}/../../assets/lenses/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).expect("the shipped lens file");
    text.lines()
        .map(|l| l.split('#').next().unwrap_or("").trim())
        .filter(|l| !l.is_empty())
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|t| t.parse().unwrap()).collect();
            [v[0], v[1], v[2], v[3]]
        })
        .collect()
}

fn prescription(name: &str, fstop: Option<f32>) -> LensPrescription {
    LensPrescription {
        source: name.into(),
        surfaces: rows(name)
            .iter()
            .map(|r| LensSurface {
                radius: r[0] as f32,
                thickness: r[1] as f32,
                ior: r[2] as f32,
                aperture: r[3] as f32,
            })
            .collect(),
        fstop,
    }
}

fn dof(focus_distance: f32) -> Dof {
    Dof {
        focus_distance,
        ..Dof::default()
    }
}

const LENSES: [&str; 2] = ["dgauss-50mm.dat", "wide-22mm.dat"];

/// Effective focal length and back focal distance (mm) of the system's ray-transfer matrix:
/// refraction `[[1, 0], [-(n2 - n1) / (n2 R), n1 / n2]]` at each surface (flat for the stop),
/// translation `[[1, t], [0, 1]]` between them; in air on both sides `EFL = -1/C`,
/// `BFD = -A/C`.
fn abcd(rows: &[[f64; 4]]) -> (f64, f64) {
    let mul = |a: [[f64; 2]; 2], b: [[f64; 2]; 2]| {
        [
            [
                a[0][0] * b[0][0] + a[0][1] * b[1][0],
                a[0][0] * b[0][1] + a[0][1] * b[1][1],
            ],
            [
                a[1][0] * b[0][0] + a[1][1] * b[1][0],
                a[1][0] * b[0][1] + a[1][1] * b[1][1],
            ],
        ]
    };
    let air = |n: f64| if n == 0.0 { 1.0 } else { n };
    let mut m = [[1.0, 0.0], [0.0, 1.0]];
    let mut n1 = 1.0;
    for (i, r) in rows.iter().enumerate() {
        let n2 = air(r[2]);
        let power = if r[0] == 0.0 {
            0.0
        } else {
            (n2 - n1) / (n2 * r[0])
        };
        m = mul([[1.0, 0.0], [-power, n1 / n2]], m);
        if i + 1 < rows.len() {
            m = mul([[1.0, r[1]], [0.0, 1.0]], m);
        }
        n1 = n2;
    }
    let (a, c) = (m[0][0], m[1][0]);
    (-1.0 / c, -a / c)
}

#[test]
fn paraxial_focal_length_and_back_focus_match_the_ray_transfer_matrices() {
    for name in LENSES {
        let (efl, bfd) = abcd(&rows(name));
        let lens = RealisticLens::new(&prescription(name, None), &dof(10.0), 640, 427).unwrap();
        let f = lens.figures;
        eprintln!(
            "{name}: EFL {:.4} mm (ABCD {efl:.4}), BFD {:.4} mm (ABCD {bfd:.4}), f/{:.3}, exit pupil radius {:.3} mm",
            f.focal_length_mm, f.back_focal_mm, f.fstop, f.exit_pupil_radius_mm
        );
        assert!((f.focal_length_mm - efl).abs() < 1e-4 * efl, "{name}: EFL");
        assert!((f.back_focal_mm - bfd).abs() < 1e-4 * efl, "{name}: BFD");
    }
    // The f-number scales the stop: f/8 asked, f/8 given (both lenses open wider than f/8).
    for name in LENSES {
        let lens = RealisticLens::new(&prescription(name, Some(8.0)), &dof(10.0), 64, 48);
        let f = lens.unwrap().figures;
        assert!((f.fstop - 8.0).abs() < 1e-6, "{name}: f/{}", f.fstop);
    }
}

/// The RMS distance from the axis (mm) of where rays from the axial point `distance` in front
/// of the film, through a grid of the front element, land on the film.
fn spot_rms_mm(lens: &RealisticLens, distance: f64, front_radius: f64) -> f64 {
    let z_front = lens.vertices()[0];
    let origin = DVec3::new(0.0, 0.0, -distance);
    let (mut sum, mut n) = (0.0, 0);
    for i in 0..64 {
        for j in 0..64 {
            let p = (DVec2::new(i as f64, j as f64) + 0.5) / 32.0 - 1.0;
            let aim = (p * front_radius).extend(z_front);
            if let Some((o, d)) = lens.trace_from_scene(origin, aim - origin) {
                let on_film = o + d * (-o.z / d.z);
                sum += on_film.truncate().length_squared();
                n += 1;
            }
        }
    }
    assert!(n > 100, "rays pass the lens");
    (sum / n as f64).sqrt() * 1e3
}

#[test]
fn a_point_at_the_focus_distance_images_to_a_spot_smaller_than_a_pixel() {
    // 640 pixels across a 36 mm film: 56 µm pixels.
    let pixel_mm = 36.0 / 640.0;
    for (name, distance, fstop) in [("dgauss-50mm.dat", 2.0, 2.8), ("wide-22mm.dat", 1.0, 4.0)] {
        let front = 0.5e-3 * rows(name)[0][3];
        let focused = RealisticLens::new(
            &prescription(name, Some(fstop)),
            &dof(distance as f32),
            640,
            427,
        )
        .unwrap();
        let spot = spot_rms_mm(&focused, distance, front);
        // The same point through the lens focused at a quarter of its distance: blurred.
        let elsewhere = RealisticLens::new(
            &prescription(name, Some(fstop)),
            &dof(0.25 * distance as f32),
            640,
            427,
        )
        .unwrap();
        let blur = spot_rms_mm(&elsewhere, distance, front);
        eprintln!("{name} f/{fstop}: spot diameter {:.4} mm in focus, {:.4} mm focused at a quarter of the distance; pixel {pixel_mm:.4} mm", 2.0 * spot, 2.0 * blur);
        assert!(2.0 * spot < pixel_mm, "{name}: in focus");
        assert!(2.0 * blur > 4.0 * pixel_mm, "{name}: out of focus");
    }
}

/// A small deterministic generator (PCG32) for the estimator comparison.
struct Pcg(u64);
impl Pcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let x = (((self.0 >> 18) ^ self.0) >> 27) as u32;
        let r = (self.0 >> 59) as u32;
        (x.rotate_right(r) >> 8) as f32 / (1u32 << 24) as f32
    }
}

/// Radiance along a camera-space ray: a checkerboard of 1 and 0.1 on the plane `z = -1.5`.
fn radiance(o: Vec3, d: Vec3) -> f32 {
    let t = (-1.5 - o.z) / d.z;
    if t.is_nan() || t <= 0.0 {
        return 0.0;
    }
    let p = o + t * d;
    let cell = ((p.x / 0.05).floor() + (p.y / 0.05).floor()) as i32;
    if cell.rem_euclid(2) == 0 {
        1.0
    } else {
        0.1
    }
}

#[test]
fn exit_pupil_sampling_matches_rear_element_sampling_with_less_variance() {
    let (w, h, n) = (24u32, 16u32, 256);
    let lens = RealisticLens::new(&prescription("dgauss-50mm.dat", None), &dof(1.5), w, h).unwrap();
    let mut var_ratio = Vec::new();
    for seed in 1..=3u64 {
        // Per sampler: the image's mean over pixels, its variance of the mean, and the mean
        // per-pixel variance of one sample.
        let mut stats = Vec::new();
        for how in [PupilSampling::ExitPupil, PupilSampling::RearElement] {
            let mut rng = Pcg(seed * 0x9e37_79b9 + 1);
            let (mut total, mut var_of_mean, mut var_sample) = (0.0f64, 0.0f64, 0.0f64);
            for y in 0..h {
                for x in 0..w {
                    let (mut s, mut s2) = (0.0f64, 0.0f64);
                    for _ in 0..n {
                        let film = Vec2::new(x as f32 + rng.next(), y as f32 + rng.next());
                        let u = Vec2::new(rng.next(), rng.next());
                        let v = lens
                            .ray(film, u, how)
                            .map_or(0.0, |(o, d, wt)| wt * radiance(o, d));
                        s += f64::from(v);
                        s2 += f64::from(v) * f64::from(v);
                    }
                    let mean = s / n as f64;
                    let var = (s2 / n as f64 - mean * mean).max(0.0);
                    total += mean;
                    var_sample += var;
                    var_of_mean += var / n as f64;
                }
            }
            let pixels = f64::from(w * h);
            stats.push((
                total / pixels,
                var_of_mean / (pixels * pixels),
                var_sample / pixels,
            ));
        }
        let (pupil, naive) = (stats[0], stats[1]);
        let sigma = (pupil.1 + naive.1).sqrt();
        eprintln!(
            "seed {seed}: image mean {:.5} (exit pupil) vs {:.5} (rear element), sigma {sigma:.5}; per-sample variance {:.4} vs {:.4}",
            pupil.0, naive.0, pupil.2, naive.2
        );
        assert!(
            (pupil.0 - naive.0).abs() < 4.0 * sigma,
            "seed {seed}: the means differ"
        );
        assert!(pupil.2 < naive.2, "seed {seed}: no variance gain");
        var_ratio.push(naive.2 / pupil.2);
    }
    eprintln!("variance gain (rear element / exit pupil): {var_ratio:?}");
}

/// The prescription camera in a render: a uniform white environment renders about 1 at the
/// image's centre (the weights are normalised there) and darker in the corners (cos⁴ and the
/// lens's own vignetting); every sample is counted (blocked rays are black, not dropped).
#[test]
fn a_uniform_environment_renders_one_at_the_centre_and_darker_corners() {
    let mut d = dof(3.0);
    d.prescription = Some(std::sync::Arc::new(prescription("wide-22mm.dat", None)));
    let cam = test_scenes::look_at_camera(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 0.8, d);
    let scene = test_scenes::scene(vec![], vec![], cam);
    let frame = Frame::still(scene, Default::default());
    let (w, h) = (33, 23);
    let opts = RenderOptions {
        width: w,
        height: h,
        spp: 256,
        env: Environment::Constant(Vec3::ONE),
        ..Default::default()
    };
    let film = frame.render(&opts, &|_, _| {}).expect("a render");
    let centre = film.pixel(w / 2, h / 2)[0];
    let corner = film.pixel(0, 0)[0];
    eprintln!("centre {centre}, corner {corner}");
    assert!((centre - 1.0).abs() < 0.03, "centre {centre}");
    assert!(corner < 0.8 * centre, "corner {corner}");
    // The same camera's rays: a blocked ray is `None`, a passing one has a finite weight.
    let camera = Camera::new(&frame_camera(&frame), w, h);
    let s = CameraSample {
        p_film: Vec2::new(0.5, 0.5),
        p_lens: Vec2::new(0.5, 0.5),
        time: 0.0,
    };
    if let Some((_, wt)) = camera.generate_ray_weighted(&s) {
        assert!(wt.is_finite() && wt > 0.0);
    }
}

fn frame_camera(frame: &Frame) -> aperture_scene::Camera {
    frame.scene().cameras[0].clone()
}
