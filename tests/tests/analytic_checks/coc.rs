//! The circle of confusion over a grid of focus, depth, radius, blades and squeeze, solved
//! exactly through the `Camera` API (no rendering).

use aperture_render::{Aperture, Camera, CameraModel, CameraSample};
use aperture_scene::Dof;
use aperture_shading::test_scenes;
use glam::{Affine3A, DVec2, DVec3, Vec2, Vec3};
use std::f64::consts::PI;

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

/// The tilted thin-lens camera of a grid point, away from the origin so the world transform
/// takes part.
fn coc_camera(case: CocCase) -> Camera {
    let dof = Dof {
        enabled: true,
        aperture_radius: case.radius,
        focus_distance: case.focus,
        blades: case.blades,
        rotation: case.rotation,
        ratio: case.ratio,
        ..Dof::default()
    };
    let sc = test_scenes::look_at_camera(
        Vec3::new(1.0, 2.0, 3.0),
        Vec3::new(0.4, 1.3, -2.0),
        0.8,
        dof,
    );
    Camera::new(&sc, COC_W, COC_H)
}

/// Finds the film position whose ray passes through a world point at depth `z`.
struct FilmSolver {
    camera_from_world: Affine3A,
    /// Depth of the point along the view axis.
    z: f64,
    /// The point in camera space.
    p_target: DVec3,
}

impl FilmSolver {
    /// Where a ray crosses the plane at depth z, in camera x, y; and the ray's origin.
    fn at_depth(&self, c: &Camera, p_film: DVec2, p_lens: Vec2) -> (DVec2, DVec3) {
        let r = c
            .generate_ray(&CameraSample {
                p_film: p_film.as_vec2(),
                p_lens,
                time: 0.0,
            })
            .expect("ray");
        let o = self.camera_from_world.transform_point3(r.origin).as_dvec3();
        let d = self.camera_from_world.transform_vector3(r.dir).as_dvec3();
        let t = (-self.z - o.z) / d.z;
        ((o + t * d).truncate(), o)
    }

    /// The film position for lens sample `p_lens`, the lens point in camera space, and how far
    /// (in pixels) the solved ray passes from the point.
    fn solve(&self, c: &Camera, p_lens: Vec2) -> (DVec2, DVec3, f64) {
        let p0 = DVec2::new(COC_W as f64 * 0.5, COC_H as f64 * 0.5);
        let step = 100.0;
        let (x0, lens) = self.at_depth(c, p0, p_lens);
        let (xx, _) = self.at_depth(c, p0 + DVec2::X * step, p_lens);
        let (xy, _) = self.at_depth(c, p0 + DVec2::Y * step, p_lens);
        let j = glam::DMat2::from_cols((xx - x0) / step, (xy - x0) / step);
        let p = p0 + j.inverse() * (self.p_target.truncate() - x0);
        let (hit, _) = self.at_depth(c, p, p_lens);
        let residual = (j.inverse() * (hit - self.p_target.truncate())).length();
        (p, lens, residual)
    }
}

/// SPEC §2: the aperture polygon's corners on the unit circle at rotation + π/n + 2πk/n,
/// counter-clockwise (none for a disc).
fn aperture_corners(case: CocCase) -> Vec<DVec2> {
    let n_blades = case.blades as f64;
    (0..case.blades)
        .map(|i| {
            let a = case.rotation as f64 + PI / n_blades + 2.0 * PI * i as f64 / n_blades;
            DVec2::new(a.cos(), a.sin())
        })
        .collect()
}

/// How far `q` lies outside the unit aperture shape (negative inside).
fn outside_shape(q: DVec2, corners: &[DVec2]) -> f64 {
    if corners.is_empty() {
        q.length() - 1.0
    } else {
        (0..corners.len())
            .map(|e| {
                let (a, b) = (corners[e], corners[(e + 1) % corners.len()]);
                // Signed distance outside edge a→b (counter-clockwise corners).
                -(b - a).perp_dot(q - a) / (b - a).length()
            })
            .fold(f64::MIN, f64::max)
    }
}

/// Area of the unit aperture shape: π for a disc, `n/2 · sin(2π/n)` for `n` blades.
fn unit_area(blades: u32) -> f64 {
    if blades == 0 {
        PI
    } else {
        let n = blades as f64;
        0.5 * n * (2.0 * PI / n).sin()
    }
}

/// Solves, for every lens sample of a `COC_LENS²` grid, the film position whose ray passes
/// through a world point at depth `depth`, using only `Camera::generate_ray`. For a fixed lens
/// sample the ray's point at a given depth is affine in the film position (SPEC §2: the focus
/// point is linear in the pixel sample, the lens point fixed), so three rays determine the map
/// and a fourth checks that the solution really hits the point.
fn coc_measure(case: CocCase) -> CocMeasure {
    let cam = coc_camera(case);
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
    let solver = FilmSolver {
        camera_from_world,
        z,
        p_target: camera_from_world.transform_point3(p_world).as_dvec3(),
    };
    let (p_pin, _, res_pin) = solver.solve(&pinhole, Vec2::ZERO);
    let (f, r) = (case.focus as f64, case.radius as f64);
    let px_per_unit = COC_H as f64 / (2.0 * tan_half_y as f64);
    // SPEC §2.
    let c_spec = r * (1.0 / f - 1.0 / z).abs() * COC_H as f64 / tan_half_y as f64;
    // Film offset per unit of lens offset: behind the focal plane (z > f) the figure keeps the
    // aperture's orientation, in front of it it is point-reflected. Raster y points down.
    let k = (1.0 / f - 1.0 / z) * px_per_unit;
    let corners = aperture_corners(case);
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
        let (p, lens, residual) = solver.solve(&cam, p_lens);
        m.residual = m.residual.max(residual);
        let offset = p - p_pin;
        let want = DVec2::new(k * lens.x, -k * lens.y);
        m.offset_error = m.offset_error.max((offset - want).length());
        film_points.push(offset);
        // The figure in units of the CoC radius, unsqueezed and un-reflected: it must be the
        // unit aperture shape.
        let q = DVec2::new(offset.x * case.ratio as f64, -offset.y) * k.signum() / (0.5 * c_spec);
        m.diameter = m.diameter.max(q.length() * c_spec);
        m.outside = m.outside.max(outside_shape(q, &corners));
    }
    let want_area = unit_area(case.blades) * (0.5 * c_spec).powi(2) / case.ratio as f64;
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
