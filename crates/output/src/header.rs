//! The EXR header of a render (SPEC §6): colour space, camera matrices, lens, date, software,
//! Cryptomatte manifests and the `aperture:*` attributes, with hashes that tell whether parts
//! of a split render belong together.

use crate::summary::RenderSummary;
use aperture_imageio::MetaValue;
use aperture_render::camera::{Camera, CameraModel};
use aperture_render::cryptomatte;
use aperture_render::film::Window;
use aperture_render::passes::{Pass, PassSet};
use aperture_render::{material_name, RenderOptions};
use aperture_scene::Scene;
use aperture_shading::environment::Environment;
use glam::{DMat4, DVec3, DVec4};

/// Rec.709 primaries and the D65 white point (CIE xy): red, green, blue, white.
pub const REC709: [f32; 8] = [0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290];

/// Header keys whose values are known only after rendering; the header holds placeholders
/// of the same type until then.
pub mod late {
    /// Seconds of rendering (f32).
    pub const RENDER_TIME: &str = "aperture:renderTime";
    /// Samples dropped as NaN or infinite (i32, saturated).
    pub const DROPPED: &str = "aperture:droppedSamples";
    /// Mean samples per pixel (f32; adaptive renders).
    pub const MEAN_SPP: &str = "aperture:meanSpp";
    /// 1 when the render was interrupted and the file holds the samples taken so far, 0 when
    /// it completed (i32; written with `--save-partial` only).
    pub const INTERRUPTED: &str = "aperture:interrupted";
}

/// Header keys that tell how parts of a render split across machines fit together (SPEC §8);
/// `aperture merge` reads them back.
pub mod split {
    /// Hash of the glTF/GLB bytes (16 hex digits): parts of one render share it.
    pub const SCENE_HASH: &str = "aperture:sceneHash";
    /// [`super::options_hash`] (16 hex digits): parts of one render share it.
    pub const OPTIONS_HASH: &str = "aperture:optionsHash";
    /// Samples per pixel of the part (i32; the most any pixel took when adaptive).
    pub const SPP: &str = "aperture:spp";
    /// First sample index of the part (i32, `--sample-offset`).
    pub const SAMPLE_OFFSET: &str = "aperture:sampleOffset";
    /// Sample index ranges a merged file holds, `A-B,C-D` (half-open); absent in a rendered
    /// part, whose one range is `sampleOffset .. sampleOffset + spp`.
    pub const SAMPLE_RANGES: &str = "aperture:sampleRanges";
    /// The part's pixels `X0,Y0,X1,Y1` (half-open), when it is not the whole image.
    pub const REGION: &str = "aperture:region";
    /// `K/N` when the part is band K of N (`--tile`).
    pub const TILE: &str = "aperture:tile";
    /// How many part files a merged file was made of (i32).
    pub const MERGED_PARTS: &str = "aperture:mergedParts";
    /// The pose the scene was rendered in ([`super::pose_text`]): parts share it, so tiles of
    /// two frames of one file are not merged into one image.
    pub const POSE: &str = "aperture:pose";
}

/// The header values known only after rendering `summary` with `opts`; with
/// `interrupted` when the file was saved partial (`Some(cancelled)`).
pub(crate) fn late_values(
    summary: &RenderSummary,
    opts: &RenderOptions,
    interrupted: Option<bool>,
) -> Vec<(String, MetaValue)> {
    let mut late = vec![
        (
            late::RENDER_TIME.to_string(),
            MetaValue::Float(summary.render_secs as f32),
        ),
        (
            late::DROPPED.to_string(),
            MetaValue::Int(summary.dropped.min(i32::MAX as u64) as i32),
        ),
    ];
    if opts.adaptive.is_some() {
        late.push((
            late::MEAN_SPP.to_string(),
            MetaValue::Float(summary.mean_spp() as f32),
        ));
    }
    if let Some(cancelled) = interrupted {
        late.push((
            late::INTERRUPTED.to_string(),
            MetaValue::Int(i32::from(cancelled)),
        ));
    }
    late
}

/// The pose of `scene` as text: `stored` for the pose in the file, else the time and the
/// animations evaluated (`t=1.25 animations=0,2`).
pub fn pose_text(scene: &Scene) -> String {
    match scene.stats.time {
        None => "stored".to_string(),
        Some(t) => {
            let played: Vec<String> = scene
                .stats
                .animations
                .iter()
                .filter(|a| a.selected)
                .map(|a| a.index.to_string())
                .collect();
            format!("t={t} animations={}", played.join(","))
        }
    }
}

/// The `X0,Y0,X1,Y1` text of a window (what `--region` takes).
pub fn region_text(w: &Window) -> String {
    let (x1, y1) = w.end();
    format!("{},{},{x1},{y1}", w.x0, w.y0)
}

/// The header attributes of a part of a split render: its sample offset and the scene's
/// pose always, its region when `window` is not the `whole` image, and `tile` (K, N) when it
/// is band K of N.
pub fn split_metadata(
    scene: &Scene,
    opts: &RenderOptions,
    (window, whole): (Window, bool),
    tile: Option<(u32, u32)>,
) -> Vec<(String, MetaValue)> {
    let mut meta = vec![
        (
            split::SAMPLE_OFFSET.to_string(),
            MetaValue::Int(opts.sample_offset.min(i32::MAX as u32) as i32),
        ),
        (split::POSE.to_string(), MetaValue::Text(pose_text(scene))),
    ];
    if !whole {
        meta.push((
            split::REGION.to_string(),
            MetaValue::Text(region_text(&window)),
        ));
    }
    if let Some((k, n)) = tile {
        meta.push((split::TILE.to_string(), MetaValue::Text(format!("{k}/{n}"))));
    }
    meta
}

/// The header of a render of `scene` through `camera` (scene camera `opts.camera`) with the
/// file's `passes`; render time, dropped samples and mean spp are placeholders (see [`late`]).
pub fn metadata(
    scene: &Scene,
    camera: &Camera,
    opts: &RenderOptions,
    passes: PassSet,
) -> Vec<(String, MetaValue)> {
    let text = |s: &str| MetaValue::Text(s.to_owned());
    let cam = scene.cameras.get(opts.camera);
    let dof = cam.map(|c| c.dof.clone()).unwrap_or_default();
    let radius = camera.aperture.radius();
    let software = format!("aperture {}", env!("CARGO_PKG_VERSION"));
    let (world_to_camera, world_to_ndc) = camera_matrices(camera, scene.world_origin);
    let mut meta: Vec<(String, MetaValue)> = vec![
        ("chromaticities".into(), MetaValue::Chromaticities(REC709)),
        ("colorInteropID".into(), text("lin_rec709_scene")),
        ("worldToCamera".into(), MetaValue::Matrix(world_to_camera)),
        ("worldToNDC".into(), MetaValue::Matrix(world_to_ndc)),
        ("focus".into(), MetaValue::Float(camera.focus_distance)),
        (
            "capDate".into(),
            text(&cap_date(std::time::SystemTime::now())),
        ),
        ("utcOffset".into(), MetaValue::Float(0.0)),
        ("software".into(), text(&software)),
        (
            "aperture:camera".into(),
            text(cam.map_or("", |c| c.name.as_str())),
        ),
        ("aperture:apertureRadius".into(), MetaValue::Float(radius)),
        (
            "aperture:focusDistance".into(),
            MetaValue::Float(camera.focus_distance),
        ),
        (
            "aperture:apertureBlades".into(),
            MetaValue::Int(dof.blades.min(i32::MAX as u32) as i32),
        ),
        (split::SPP.into(), MetaValue::Int(opts.spp as i32)),
        ("aperture:seed".into(), MetaValue::Int(opts.seed as i32)),
        (late::RENDER_TIME.into(), MetaValue::Float(0.0)),
        (
            "aperture:maxBounces".into(),
            MetaValue::Int(opts.max_bounces.min(i32::MAX as u32) as i32),
        ),
        (
            "aperture:sampler".into(),
            text(&format!("{:?}", opts.sampler)),
        ),
        (
            "aperture:filter".into(),
            text(&format!("{:?}", opts.filter)),
        ),
        (late::DROPPED.into(), MetaValue::Int(0)),
        ("aperture:software".into(), text(&software)),
        (
            split::SCENE_HASH.into(),
            text(&format!("{:016x}", scene.source_hash)),
        ),
        (
            split::OPTIONS_HASH.into(),
            text(&format!("{:016x}", options_hash(opts))),
        ),
    ];
    if radius > 0.0 && dof.lens_mm > 0.0 {
        // f-number N from R = lens / (2 N), lens in mm and 1 unit = 1 m (SPEC §3).
        let f_number = dof.lens_mm * 0.001 / (2.0 * radius);
        meta.push(("aperture".into(), MetaValue::Float(f_number)));
    }
    meta.extend(sampling_metadata(opts));
    meta.extend(cryptomatte_metadata(scene, passes));
    meta
}

/// The header values of adaptive sampling and of Cycles' clamps, when they are on.
fn sampling_metadata(opts: &RenderOptions) -> Vec<(String, MetaValue)> {
    let mut meta = Vec::new();
    if let Some(a) = opts.adaptive {
        meta.push((
            "aperture:noiseThreshold".into(),
            MetaValue::Float(a.threshold),
        ));
        meta.push(("aperture:minSpp".into(), MetaValue::Int(a.min_spp as i32)));
        meta.push((late::MEAN_SPP.into(), MetaValue::Float(0.0)));
    }
    // A clamped image is biased; the header says so, so a compositor can tell.
    for (key, v) in [
        ("aperture:clampDirect", opts.clamp.direct),
        ("aperture:clampIndirect", opts.clamp.indirect),
    ] {
        if v > 0.0 {
            meta.push((key.to_string(), MetaValue::Float(v)));
        }
    }
    meta
}

/// The Cryptomatte layers' header values (name, hash, conversion, manifest) for the
/// Cryptomatte passes among `passes`.
fn cryptomatte_metadata(scene: &Scene, passes: PassSet) -> Vec<(String, MetaValue)> {
    let text = |s: &str| MetaValue::Text(s.to_owned());
    let mut meta = Vec::new();
    for pass in [Pass::CryptoObject, Pass::CryptoMaterial] {
        if !passes.contains(pass) {
            continue;
        }
        let names: Vec<String> = if pass == Pass::CryptoObject {
            scene
                .instances
                .iter()
                .map(|i| scene.node_name(i.node))
                .collect()
        } else {
            (0..scene.materials.len())
                .map(|m| material_name(scene, m))
                .collect()
        };
        let key = cryptomatte::layer_key(pass.name());
        let at = |field: &str| format!("cryptomatte/{key}/{field}");
        meta.push((at("name"), text(pass.name())));
        meta.push((at("hash"), text("MurmurHash3_32")));
        meta.push((at("conversion"), text("uint32_to_float32")));
        let manifest = cryptomatte::manifest(names.iter().map(String::as_str));
        meta.push((at("manifest"), MetaValue::Text(manifest)));
    }
    meta
}

/// OpenEXR's `worldToCamera` and `worldToNDC` (as stored: Imath row-vector matrices, 16
/// values row by row) for `camera`, in the glTF file's world (`world_origin` added back).
///
/// Camera space is OpenEXR's (RenderMan's): x right, y up, z along the view (left-handed).
/// NDC: (0, 0) at the top-left corner of the display window and (1, 1) at the bottom-right;
/// a world point `p` lands at `(x/w, y/w)` of `[p, 1] · worldToNDC = [x, y, z, w]`.
pub fn camera_matrices(camera: &Camera, world_origin: DVec3) -> ([f32; 16], [f32; 16]) {
    let m = camera.world_from_camera;
    let world_from_camera = DMat4::from_cols(
        DVec4::from((m.matrix3.x_axis.as_dvec3(), 0.0)),
        DVec4::from((m.matrix3.y_axis.as_dvec3(), 0.0)),
        DVec4::from((m.matrix3.z_axis.as_dvec3(), 0.0)),
        DVec4::from((m.translation.as_dvec3() + world_origin, 1.0)),
    );
    // Ours looks down −Z; OpenEXR's camera looks down +Z.
    let flip = DMat4::from_diagonal(DVec4::new(1.0, 1.0, -1.0, 1.0));
    let camera_from_world = flip * world_from_camera.inverse();
    let ndc_from_camera = match camera.model {
        CameraModel::ThinLens {
            tan_half_x,
            tan_half_y,
        } => {
            let (tx, ty) = (f64::from(tan_half_x), f64::from(tan_half_y));
            // Rows: x = 0.5 X/tx + 0.5 Z, y = −0.5 Y/ty + 0.5 Z, z = 1, w = Z.
            DMat4::from_cols(
                DVec4::new(0.5 / tx, 0.0, 0.0, 0.0),
                DVec4::new(0.0, -0.5 / ty, 0.0, 0.0),
                DVec4::new(0.5, 0.5, 0.0, 1.0),
                DVec4::new(0.0, 0.0, 1.0, 0.0),
            )
        }
        CameraModel::Orthographic { half_x, half_y } => {
            let (hx, hy) = (f64::from(half_x), f64::from(half_y));
            DMat4::from_cols(
                DVec4::new(0.5 / hx, 0.0, 0.0, 0.0),
                DVec4::new(0.0, -0.5 / hy, 0.0, 0.0),
                DVec4::new(0.0, 0.0, 1.0, 0.0),
                DVec4::new(0.5, 0.5, 0.0, 1.0),
            )
        }
    };
    // A column-vector matrix's columns are the row-vector matrix's rows.
    let stored = |k: DMat4| k.to_cols_array().map(|v| v as f32);
    (
        stored(camera_from_world),
        stored(ndc_from_camera * camera_from_world),
    )
}

/// `capDate` for `t`: `YYYY:MM:DD hh:mm:ss`, in UTC (with `utcOffset` 0 beside it).
fn cap_date(t: std::time::SystemTime) -> String {
    let secs = t
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rest) = ((secs / 86_400) as i64, secs % 86_400);
    // Howard Hinnant's civil-from-days.
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}:{month:02}:{day:02} {:02}:{:02}:{:02}",
        rest / 3600,
        rest / 60 % 60,
        rest % 60
    )
}

/// A hash of every option that changes pixel values, whatever the sample range or region:
/// parts of one render split across machines share it. `spp` and `sample_offset` are left
/// out (they say which samples a part holds, which merge checks on its own), and so is the
/// `Debug Sample Count` pass, which files of tiles and batches get and a whole render may not.
pub fn options_hash(opts: &RenderOptions) -> u64 {
    let mut bytes = format!(
        "{}x{} camera {} seed {} bounces {} {:?} {:?} {:?} {:?} {:?} {:?}",
        opts.width,
        opts.height,
        opts.camera,
        opts.seed,
        opts.max_bounces,
        opts.filter,
        opts.sampler,
        opts.material_override,
        opts.clamp,
        opts.adaptive,
        // The passes as a set (its Debug form), the sample count left out.
        opts.passes
            .iter()
            .filter(|&p| p != Pass::SampleCount)
            .collect::<PassSet>(),
    )
    .into_bytes();
    // Only with motion blur, so the hash of a render without it is what it always was.
    if let Some(m) = &opts.motion {
        let motion = format!(" motion {:?} {:?} {:?}", m.shutter, m.interval, m.camera);
        bytes.extend(motion.bytes());
    }
    match &opts.env {
        Environment::Constant(c) => bytes.extend(format!(" env {c:?}").bytes()),
        Environment::Image(im) => {
            let header = format!(
                " env {}x{} {:?} {:?} {:?} ",
                im.width, im.height, im.rotation, im.strength, im.sampling
            );
            bytes.extend(header.bytes());
            for t in &im.texels {
                for c in t.to_array() {
                    bytes.extend(c.to_le_bytes());
                }
            }
        }
    }
    aperture_scene::content_hash(&bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use aperture_shading::test_scenes;
    use glam::{Vec2, Vec3};

    #[test]
    fn dates_are_civil() {
        let at = |s: u64| cap_date(std::time::UNIX_EPOCH + std::time::Duration::from_secs(s));
        assert_eq!(at(0), "1970:01:01 00:00:00");
        assert_eq!(at(951_782_400), "2000:02:29 00:00:00");
        assert_eq!(at(1_795_437_296), "2026:11:23 12:34:56");
    }

    /// worldToNDC sends the point a pixel's centre ray passes through to that pixel's centre
    /// in NDC, for perspective and orthographic cameras, and worldToCamera puts it at positive
    /// z along the view.
    #[test]
    fn matrices_project_points_onto_their_pixels() {
        let scene = test_scenes::lit_plane(1.0);
        let mut cam = scene.cameras[0].clone();
        let origin = DVec3::new(1e3, -2.0, 5.0);
        for ortho in [false, true] {
            if ortho {
                cam.projection = aperture_scene::Projection::Orthographic {
                    xmag: 3.0,
                    ymag: 2.0,
                };
            }
            let camera = Camera::new(&cam, 64, 48);
            let (w2c, w2n) = camera_matrices(&camera, origin);
            let apply = |m: &[f32; 16], p: DVec3| -> DVec4 {
                let row = DVec4::from((p, 1.0));
                DVec4::new(
                    (0..4).map(|r| row[r] * f64::from(m[r * 4])).sum(),
                    (0..4).map(|r| row[r] * f64::from(m[r * 4 + 1])).sum(),
                    (0..4).map(|r| row[r] * f64::from(m[r * 4 + 2])).sum(),
                    (0..4).map(|r| row[r] * f64::from(m[r * 4 + 3])).sum(),
                )
            };
            for (px, py) in [(0.5f32, 0.5f32), (40.5, 11.5), (63.5, 47.5)] {
                let ray = camera.centre_ray(Vec2::new(px, py)).unwrap();
                let p = ray.origin + ray.dir * 7.0;
                let file_p = p.as_dvec3() + origin;
                let c = apply(&w2c, file_p);
                assert!(c.z > 0.0, "in front: {c}");
                let n = apply(&w2n, file_p);
                let (x, y) = (n.x / n.w * 64.0, n.y / n.w * 48.0);
                assert!(
                    (x - f64::from(px)).abs() < 1e-3 && (y - f64::from(py)).abs() < 1e-3,
                    "ortho {ortho}: ({px}, {py}) -> ({x}, {y})"
                );
            }
            let _ = Vec3::ZERO;
        }
    }

    #[test]
    fn options_hash_ignores_sample_count_but_not_seed() {
        let a = RenderOptions::default();
        let more = RenderOptions {
            spp: 128,
            sample_offset: 64,
            ..a.clone()
        };
        let seeded = RenderOptions {
            seed: 3,
            ..a.clone()
        };
        assert_eq!(options_hash(&a), options_hash(&more));
        let counted = RenderOptions {
            passes: a.passes.with(Pass::SampleCount),
            ..a.clone()
        };
        assert_eq!(options_hash(&a), options_hash(&counted));
        assert_ne!(options_hash(&a), options_hash(&seeded));
    }
}
