//! Depth of field resolved from every source of SPEC §3.
//!
//! Sources, lowest precedence first: defaults → `EXT_camera_physical` → `cameras[i].extras` →
//! `nodes[j].extras` → command line. Each source is parsed into a [`Layer`] of optional values, and
//! a later layer overrides an earlier one key by key, with two pairs decided per source rather than
//! per key, so that a higher source always wins:
//! - the aperture: the highest source giving `aperture_radius` or `aperture_fstop` decides, and
//!   inside it `aperture_radius` wins over `aperture_fstop`;
//! - the focus: the highest source giving `focus_object` or `focus_distance` decides, and inside it
//!   `focus_object` wins over `focus_distance`.
//!
//! `use_dof` defaults to on when any source gives an aperture. An aperture given on the command
//! line turns depth of field on even if the file says `use_dof: false` (unless `--no-dof`): the
//! user asked for it explicitly.

use glam::{Affine3A, Vec3};
use serde_json::Value;

use crate::{Dof, DofOverrides, Error, Projection, SensorFit};

/// Blender's default image aspect (36 × 24 mm sensor) when a camera has no `aspectRatio`.
pub const DEFAULT_ASPECT: f32 = 1.5;

/// The node a `focus_object` names.
#[derive(Debug, Clone, PartialEq)]
enum FocusTarget {
    Name(String),
    Index(usize),
}

/// One source's values; `None` = not given by this source.
#[derive(Debug, Clone, Default)]
struct Layer {
    use_dof: Option<bool>,
    aperture_radius: Option<f32>,
    aperture_fstop: Option<f32>,
    lens: Option<f32>,
    sensor_width: Option<f32>,
    sensor_height: Option<f32>,
    sensor_fit: Option<SensorFit>,
    focus_distance: Option<f32>,
    focus_object: Option<FocusTarget>,
    blades: Option<u32>,
    rotation: Option<f32>,
    ratio: Option<f32>,
}

/// What the resolver needs to know about the scene's nodes for `focus_object`.
pub(crate) struct NodeInfo<'a> {
    /// Node names by index.
    pub names: &'a [Option<String>],
    /// World-space origin of every node.
    pub origins: &'a [Vec3],
}

/// The inputs for one camera.
pub(crate) struct CameraInput<'a> {
    /// Camera name for messages.
    pub name: &'a str,
    /// Projection (for the lens derived from `yfov`).
    pub projection: Projection,
    /// Camera-to-world transform (rotation + translation).
    pub world_from_camera: Affine3A,
    /// `cameras[i].extensions.EXT_camera_physical`.
    pub physical: Option<&'a Value>,
    /// `cameras[i].extras`.
    pub camera_extras: Option<&'a Value>,
    /// `nodes[j].extras`.
    pub node_extras: Option<&'a Value>,
}

struct Ctx<'a> {
    camera: &'a str,
    prefix: &'a str,
}

impl Ctx<'_> {
    fn err(&self, key: &str, value: impl std::fmt::Display, reason: &str) -> Error {
        Error::InvalidDof {
            camera: self.camera.into(),
            key: format!("{}{key}", self.prefix),
            value: value.to_string(),
            reason: reason.into(),
        }
    }

    fn number(&self, key: &str, v: &Value) -> Result<f32, Error> {
        let x = v
            .as_f64()
            .ok_or_else(|| self.err(key, v, "expected a number"))?;
        let x = x as f32;
        if !x.is_finite() {
            return Err(self.err(key, v, "not a finite 32-bit number"));
        }
        Ok(x)
    }

    fn positive(&self, key: &str, v: &Value) -> Result<f32, Error> {
        let x = self.number(key, v)?;
        if x <= 0.0 {
            return Err(self.err(key, v, "must be > 0"));
        }
        Ok(x)
    }

    fn check_positive(&self, key: &str, x: f32) -> Result<f32, Error> {
        if !x.is_finite() || x <= 0.0 {
            return Err(self.err(key, x, "must be a finite number > 0"));
        }
        Ok(x)
    }
}

/// Parses Blender's keys from an `extras` object. Unknown keys are ignored; a non-object `extras`
/// carries no depth-of-field keys.
fn parse_extras(extras: Option<&Value>, ctx: &Ctx<'_>) -> Result<Layer, Error> {
    let mut l = Layer::default();
    let Some(map) = extras.and_then(Value::as_object) else {
        return Ok(l);
    };
    for (key, v) in map {
        match key.as_str() {
            "use_dof" => {
                // Blender stores booleans of older custom properties as 0/1 integers.
                l.use_dof = Some(match v {
                    Value::Bool(b) => *b,
                    Value::Number(n) if n.as_u64() == Some(0) => false,
                    Value::Number(n) if n.as_u64() == Some(1) => true,
                    _ => return Err(ctx.err(key, v, "expected true or false")),
                })
            }
            "aperture_radius" => {
                let x = ctx.number(key, v)?;
                if x < 0.0 {
                    return Err(ctx.err(key, v, "must be >= 0"));
                }
                l.aperture_radius = Some(x);
            }
            "aperture_fstop" => l.aperture_fstop = Some(ctx.positive(key, v)?),
            "lens" => l.lens = Some(ctx.positive(key, v)?),
            "sensor_width" => l.sensor_width = Some(ctx.positive(key, v)?),
            "sensor_height" => l.sensor_height = Some(ctx.positive(key, v)?),
            "sensor_fit" => {
                l.sensor_fit = Some(match v.as_str().map(str::to_ascii_uppercase).as_deref() {
                    Some("AUTO") => SensorFit::Auto,
                    Some("HORIZONTAL") => SensorFit::Horizontal,
                    Some("VERTICAL") => SensorFit::Vertical,
                    _ => {
                        return Err(ctx.err(
                            key,
                            v,
                            "expected \"AUTO\", \"HORIZONTAL\" or \"VERTICAL\"",
                        ))
                    }
                })
            }
            "focus_distance" => l.focus_distance = Some(ctx.positive(key, v)?),
            "focus_object" => {
                l.focus_object = Some(match v {
                    Value::String(s) => FocusTarget::Name(s.clone()),
                    Value::Number(n) => FocusTarget::Index(
                        n.as_u64()
                            .and_then(|i| usize::try_from(i).ok())
                            .ok_or_else(|| {
                                ctx.err(key, v, "a node index must be an integer >= 0")
                            })?,
                    ),
                    Value::Object(o) => match o.get("name") {
                        Some(Value::String(s)) => FocusTarget::Name(s.clone()),
                        _ => {
                            return Err(ctx.err(
                                key,
                                v,
                                "expected {\"name\": \"...\", \"type\": \"Object\"}",
                            ))
                        }
                    },
                    _ => {
                        return Err(ctx.err(
                            key,
                            v,
                            "expected a node name, index or {\"name\": ...}",
                        ))
                    }
                })
            }
            "aperture_blades" => {
                let n = v
                    .as_f64()
                    .filter(|x| x.fract() == 0.0 && *x >= 0.0 && *x <= u32::MAX as f64)
                    .ok_or_else(|| ctx.err(key, v, "expected an integer 0 or >= 3"))?
                    as u32;
                if n == 1 || n == 2 {
                    return Err(ctx.err(key, v, "a polygon needs at least 3 blades (0 = round)"));
                }
                l.blades = Some(n);
            }
            "aperture_rotation" => l.rotation = Some(ctx.number(key, v)?),
            "aperture_ratio" => l.ratio = Some(ctx.positive(key, v)?),
            _ => {}
        }
    }
    Ok(l)
}

/// Parses the draft `EXT_camera_physical` (metres) into Blender's units (mm for lens and sensor).
fn parse_physical(ext: Option<&Value>, ctx: &Ctx<'_>) -> Result<Layer, Error> {
    let mut l = Layer::default();
    let Some(map) = ext.and_then(Value::as_object) else {
        return Ok(l);
    };
    if let Some(v) = map.get("focalLength") {
        l.lens = Some(ctx.positive("focalLength", v)? * 1000.0);
    }
    if let Some(v) = map.get("sensorSize") {
        let pair = v
            .as_array()
            .filter(|a| a.len() == 2)
            .ok_or_else(|| ctx.err("sensorSize", v, "expected [width, height] in metres"))?;
        l.sensor_width = Some(ctx.positive("sensorSize", &pair[0])? * 1000.0);
        l.sensor_height = Some(ctx.positive("sensorSize", &pair[1])? * 1000.0);
    }
    if let Some(v) = map.get("fStop") {
        l.aperture_fstop = Some(ctx.positive("fStop", v)?);
    }
    if let Some(v) = map.get("focusDistance") {
        l.focus_distance = Some(ctx.positive("focusDistance", v)?);
    }
    Ok(l)
}

/// The command-line layer, validated like the file's values.
fn parse_overrides(o: &DofOverrides, ctx: &Ctx<'_>) -> Result<Layer, Error> {
    let mut l = Layer {
        use_dof: o.use_dof,
        ..Layer::default()
    };
    if let Some(r) = o.aperture_radius {
        if !r.is_finite() || r < 0.0 {
            return Err(ctx.err("aperture_radius", r, "must be a finite number >= 0"));
        }
        l.aperture_radius = Some(r);
    }
    if let Some(f) = o.aperture_fstop {
        l.aperture_fstop = Some(ctx.check_positive("aperture_fstop", f)?);
    }
    if let Some(d) = o.focus_distance {
        l.focus_distance = Some(ctx.check_positive("focus_distance", d)?);
    }
    if let Some(name) = &o.focus_object {
        l.focus_object = Some(match name.parse::<usize>() {
            Ok(i) if name.bytes().all(|b| b.is_ascii_digit()) => FocusTarget::Index(i),
            _ => FocusTarget::Name(name.clone()),
        });
    }
    if l.use_dof.is_none() && (l.aperture_radius.is_some() || l.aperture_fstop.is_some()) {
        l.use_dof = Some(true);
    }
    Ok(l)
}

/// Blender's focal length for a vertical field of view (SPEC §3, `lens` default).
pub fn lens_from_yfov(
    yfov: f32,
    aspect: f32,
    sensor_width: f32,
    sensor_height: f32,
    fit: SensorFit,
) -> f32 {
    let t = (0.5 * yfov).tan();
    match fit {
        SensorFit::Auto if aspect >= 1.0 => sensor_width / (2.0 * aspect * t),
        SensorFit::Auto => sensor_width / (2.0 * t),
        SensorFit::Horizontal => sensor_width / (2.0 * aspect * t),
        SensorFit::Vertical => sensor_height / (2.0 * t),
    }
}

/// Resolves a camera's depth of field from every source.
pub(crate) fn resolve(
    cam: &CameraInput<'_>,
    overrides: &DofOverrides,
    nodes: &NodeInfo<'_>,
) -> Result<Dof, Error> {
    let ctx = |prefix| Ctx {
        camera: cam.name,
        prefix,
    };
    let layers = [
        parse_physical(cam.physical, &ctx("EXT_camera_physical."))?,
        parse_extras(cam.camera_extras, &ctx("cameras.extras."))?,
        parse_extras(cam.node_extras, &ctx("nodes.extras."))?,
        parse_overrides(overrides, &ctx("command line "))?,
    ];
    let last = |f: &dyn Fn(&Layer) -> Option<f32>| layers.iter().rev().find_map(f);
    let d = Dof::default();
    let sensor_width = last(&|l| l.sensor_width).unwrap_or(d.sensor_width);
    let sensor_height = last(&|l| l.sensor_height).unwrap_or(d.sensor_height);
    let sensor_fit = layers
        .iter()
        .rev()
        .find_map(|l| l.sensor_fit)
        .unwrap_or_default();
    let lens_mm = match (last(&|l| l.lens), cam.projection) {
        (Some(lens), _) => lens,
        (None, Projection::Perspective { yfov, aspect_ratio }) => {
            let aspect = aspect_ratio
                .filter(|a| a.is_finite() && *a > 0.0)
                .unwrap_or(DEFAULT_ASPECT);
            lens_from_yfov(yfov, aspect, sensor_width, sensor_height, sensor_fit)
        }
        (None, Projection::Orthographic { .. }) => d.lens_mm,
    };

    let aperture_layer = layers
        .iter()
        .rev()
        .find(|l| l.aperture_radius.is_some() || l.aperture_fstop.is_some());
    let aperture_radius = match aperture_layer {
        Some(Layer {
            aperture_radius: Some(r),
            ..
        }) => *r,
        Some(Layer {
            aperture_fstop: Some(f),
            ..
        }) => lens_mm * 0.001 / (2.0 * f),
        _ => 0.0,
    };
    let enabled = layers
        .iter()
        .rev()
        .find_map(|l| l.use_dof)
        .unwrap_or(aperture_layer.is_some());

    let focus_layer = layers
        .iter()
        .enumerate()
        .rev()
        .find(|(_, l)| l.focus_object.is_some() || l.focus_distance.is_some());
    let prefixes = [
        "EXT_camera_physical.",
        "cameras.extras.",
        "nodes.extras.",
        "command line ",
    ];
    let (focus_distance, focus_object) = match focus_layer {
        Some((i, l)) => match (&l.focus_object, l.focus_distance) {
            (Some(target), _) => {
                let c = ctx(prefixes[i]);
                let (index, shown) = match target {
                    FocusTarget::Name(n) => (
                        nodes
                            .names
                            .iter()
                            .position(|m| m.as_deref() == Some(n.as_str()))
                            .ok_or_else(|| {
                                c.err("focus_object", format!("{n:?}"), "no node has this name")
                            })?,
                        format!("{n:?}"),
                    ),
                    FocusTarget::Index(i) => {
                        if *i >= nodes.origins.len() {
                            return Err(c.err(
                                "focus_object",
                                i,
                                &format!("no such node (the file has {})", nodes.origins.len()),
                            ));
                        }
                        (*i, i.to_string())
                    }
                };
                let p = nodes.origins[index];
                let forward = -cam.world_from_camera.matrix3.z_axis;
                let depth =
                    Vec3::from(forward).dot(p - Vec3::from(cam.world_from_camera.translation));
                if depth.is_nan() || depth <= 0.0 {
                    return Err(c.err(
                        "focus_object",
                        shown,
                        &format!("the focus point is not in front of the camera (depth {depth})"),
                    ));
                }
                let name = nodes
                    .names
                    .get(index)
                    .cloned()
                    .flatten()
                    .unwrap_or_else(|| format!("nodes[{index}]"));
                (depth, Some(name))
            }
            (None, Some(dist)) => (dist, None),
            (None, None) => (d.focus_distance, None),
        },
        None => (d.focus_distance, None),
    };

    Ok(Dof {
        enabled,
        aperture_radius,
        focus_distance,
        lens_mm,
        sensor_width,
        sensor_height,
        sensor_fit,
        blades: layers
            .iter()
            .rev()
            .find_map(|l| l.blades)
            .unwrap_or(d.blades),
        rotation: last(&|l| l.rotation).unwrap_or(d.rotation),
        ratio: last(&|l| l.ratio).unwrap_or(d.ratio),
        focus_object,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    const YFOV: f32 = 0.5;

    fn persp(aspect: Option<f32>) -> Projection {
        Projection::Perspective {
            yfov: YFOV,
            aspect_ratio: aspect,
        }
    }

    struct Case {
        projection: Projection,
        physical: Option<Value>,
        camera: Option<Value>,
        node: Option<Value>,
        cli: DofOverrides,
        world_from_camera: Affine3A,
    }

    impl Default for Case {
        fn default() -> Self {
            Self {
                projection: persp(Some(1.5)),
                physical: None,
                camera: None,
                node: None,
                cli: DofOverrides::default(),
                world_from_camera: Affine3A::IDENTITY,
            }
        }
    }

    fn names() -> Vec<Option<String>> {
        vec![
            Some("Cam".into()),
            Some("Target".into()),
            None,
            Some("Behind".into()),
        ]
    }
    fn origins() -> Vec<Vec3> {
        vec![
            Vec3::ZERO,
            Vec3::new(1.0, 2.0, -7.0),
            Vec3::new(0.0, 0.0, -3.0),
            Vec3::new(0.0, 0.0, 4.0),
        ]
    }

    fn run(c: &Case) -> Result<Dof, Error> {
        let (names, origins) = (names(), origins());
        resolve(
            &CameraInput {
                name: "Camera",
                projection: c.projection,
                world_from_camera: c.world_from_camera,
                physical: c.physical.as_ref(),
                camera_extras: c.camera.as_ref(),
                node_extras: c.node.as_ref(),
            },
            &c.cli,
            &NodeInfo {
                names: &names,
                origins: &origins,
            },
        )
    }

    fn close(a: f32, b: f32) -> bool {
        (a - b).abs() <= 1e-5 * b.abs().max(1.0)
    }

    #[test]
    fn defaults_are_a_pinhole_with_blender_values() {
        let d = run(&Case::default()).unwrap();
        assert!(!d.enabled);
        assert_eq!(d.effective_radius(), 0.0);
        assert_eq!(d.focus_distance, 10.0);
        assert_eq!((d.sensor_width, d.sensor_height), (36.0, 24.0));
    }

    #[test]
    fn lens_derived_from_yfov_for_every_fit() {
        let t = (YFOV / 2.0).tan();
        // Landscape AUTO: the 36 mm width spans the image width.
        let d = run(&Case::default()).unwrap();
        assert!(close(d.lens_mm, 36.0 / (2.0 * 1.5 * t)));
        // Missing aspect ratio: Blender's 1.5.
        let d = run(&Case {
            projection: persp(None),
            ..Case::default()
        })
        .unwrap();
        assert!(close(d.lens_mm, 36.0 / (2.0 * 1.5 * t)));
        // Portrait AUTO: the 36 mm width spans the image height.
        let d = run(&Case {
            projection: persp(Some(0.5)),
            ..Case::default()
        })
        .unwrap();
        assert!(close(d.lens_mm, 36.0 / (2.0 * t)));
        let d = run(&Case {
            projection: persp(Some(0.5)),
            camera: Some(json!({"sensor_fit": "HORIZONTAL"})),
            ..Case::default()
        })
        .unwrap();
        assert!(close(d.lens_mm, 36.0 / (2.0 * 0.5 * t)));
        let d = run(&Case {
            camera: Some(json!({"sensor_fit": "VERTICAL", "sensor_height": 20.0})),
            ..Case::default()
        })
        .unwrap();
        assert!(close(d.lens_mm, 20.0 / (2.0 * t)));
        assert_eq!(d.sensor_fit, SensorFit::Vertical);
    }

    #[test]
    fn fstop_with_derived_lens_gives_cycles_radius_and_turns_dof_on() {
        let d = run(&Case {
            camera: Some(json!({"aperture_fstop": 2.8})),
            ..Case::default()
        })
        .unwrap();
        let lens = 36.0 / (2.0 * 1.5 * (YFOV / 2.0).tan());
        assert!(d.enabled);
        assert!(close(d.aperture_radius, lens * 0.001 / (2.0 * 2.8)));
    }

    #[test]
    fn fstop_with_given_lens() {
        let d = run(&Case {
            camera: Some(json!({"aperture_fstop": 2.0, "lens": 50})),
            ..Case::default()
        })
        .unwrap();
        assert!(close(d.aperture_radius, 0.0125));
        assert_eq!(d.lens_mm, 50.0);
    }

    #[test]
    fn radius_wins_over_fstop_in_the_same_source() {
        let d = run(&Case {
            camera: Some(json!({"aperture_fstop": 2.0, "aperture_radius": 0.3})),
            ..Case::default()
        })
        .unwrap();
        assert_eq!(d.aperture_radius, 0.3);
    }

    #[test]
    fn precedence_physical_camera_node_cli() {
        let mut c = Case {
            physical: Some(json!({"focusDistance": 1.0, "fStop": 4.0, "focalLength": 0.035})),
            ..Case::default()
        };
        assert_eq!(run(&c).unwrap().focus_distance, 1.0);
        assert_eq!(run(&c).unwrap().lens_mm, 35.0);
        c.camera = Some(json!({"focus_distance": 2.0, "lens": 70}));
        assert_eq!(run(&c).unwrap().focus_distance, 2.0);
        assert_eq!(run(&c).unwrap().lens_mm, 70.0);
        c.node = Some(json!({"focus_distance": 3.0}));
        let d = run(&c).unwrap();
        assert_eq!(d.focus_distance, 3.0);
        assert_eq!(
            d.lens_mm, 70.0,
            "node extras without lens keep the camera's"
        );
        c.cli.focus_distance = Some(4.0);
        assert_eq!(run(&c).unwrap().focus_distance, 4.0);
    }

    #[test]
    fn node_extras_override_camera_extras() {
        let d = run(&Case {
            camera: Some(json!({"aperture_radius": 0.1, "use_dof": false, "aperture_blades": 6})),
            node: Some(json!({"aperture_fstop": 2.0, "use_dof": true, "lens": 50})),
            ..Case::default()
        })
        .unwrap();
        // The node's f-stop wins over the camera's radius: the higher source decides the aperture.
        assert!(close(d.aperture_radius, 0.0125));
        assert!(d.enabled);
        assert_eq!(d.blades, 6);
    }

    #[test]
    fn ext_camera_physical_units() {
        let d = run(&Case {
            physical: Some(json!({"focalLength": 0.05, "sensorSize": [0.036, 0.018], "fStop": 2.0, "focusDistance": 3.5})),
            ..Case::default()
        })
        .unwrap();
        assert!(close(d.lens_mm, 50.0));
        assert!(close(d.sensor_width, 36.0) && close(d.sensor_height, 18.0));
        assert!(close(d.aperture_radius, 0.0125));
        assert_eq!(d.focus_distance, 3.5);
        assert!(d.enabled);
    }

    #[test]
    fn use_dof_false_disables_a_given_aperture() {
        let d = run(&Case {
            camera: Some(json!({"aperture_radius": 0.2, "use_dof": false})),
            ..Case::default()
        })
        .unwrap();
        assert!(!d.enabled);
        assert_eq!(d.effective_radius(), 0.0);
        let mut c = Case {
            camera: Some(json!({"aperture_radius": 0.2})),
            ..Case::default()
        };
        c.cli.use_dof = Some(false);
        assert!(!run(&c).unwrap().enabled);
        // An aperture on the command line asks for depth of field.
        let mut c = Case {
            camera: Some(json!({"use_dof": false})),
            ..Case::default()
        };
        c.cli.aperture_fstop = Some(1.4);
        assert!(run(&c).unwrap().enabled);
    }

    #[test]
    fn focus_object_by_name_index_and_blender_form() {
        for fo in [
            json!("Target"),
            json!(1),
            json!({"name": "Target", "type": "Object"}),
        ] {
            let d = run(&Case {
                camera: Some(json!({"focus_object": fo, "focus_distance": 2.0})),
                ..Case::default()
            })
            .unwrap();
            assert!(close(d.focus_distance, 7.0), "{fo}: {}", d.focus_distance);
            assert_eq!(d.focus_object.as_deref(), Some("Target"));
        }
        // Depth is measured along the view axis of a moved and turned camera.
        let d = run(&Case {
            node: Some(json!({"focus_object": 2})),
            world_from_camera: Affine3A::from_rotation_translation(
                glam::Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
                Vec3::new(5.0, 0.0, -3.0),
            ),
            ..Case::default()
        })
        .unwrap();
        // The camera at x = 5 looks down −X; the node at x = 0 is 5 in front of it.
        assert!(close(d.focus_distance, 5.0), "{}", d.focus_distance);
        assert_eq!(d.focus_object.as_deref(), Some("nodes[2]"));
    }

    #[test]
    fn cli_focus_object_and_distance_precedence() {
        let mut c = Case {
            camera: Some(json!({"focus_object": "Target"})),
            ..Case::default()
        };
        c.cli.focus_distance = Some(3.0);
        let d = run(&c).unwrap();
        assert_eq!(d.focus_distance, 3.0);
        assert_eq!(d.focus_object, None);
        c.cli.focus_object = Some("2".into());
        assert!(close(run(&c).unwrap().focus_distance, 3.0));
        c.cli.focus_object = Some("Target".into());
        assert!(close(run(&c).unwrap().focus_distance, 7.0));
    }

    fn invalid(camera: Value) -> String {
        let e = run(&Case {
            camera: Some(camera.clone()),
            ..Case::default()
        })
        .expect_err(&camera.to_string());
        assert!(matches!(e, Error::InvalidDof { .. }));
        let s = e.to_string();
        assert!(s.contains("\"Camera\""), "{s}");
        s
    }

    #[test]
    fn each_invalid_value_names_camera_key_and_value() {
        for (extras, key) in [
            (json!({"aperture_radius": -0.1}), "aperture_radius"),
            (json!({"aperture_radius": "wide"}), "aperture_radius"),
            (json!({"aperture_fstop": 0}), "aperture_fstop"),
            (json!({"aperture_fstop": -2}), "aperture_fstop"),
            (json!({"lens": 0}), "lens"),
            (json!({"sensor_width": -36}), "sensor_width"),
            (json!({"sensor_height": null}), "sensor_height"),
            (json!({"sensor_fit": "DIAGONAL"}), "sensor_fit"),
            (json!({"focus_distance": 0}), "focus_distance"),
            (json!({"focus_distance": 1e300}), "focus_distance"),
            (json!({"focus_object": "Nobody"}), "focus_object"),
            (json!({"focus_object": 99}), "focus_object"),
            (json!({"focus_object": -1}), "focus_object"),
            (json!({"focus_object": {"type": "Object"}}), "focus_object"),
            (json!({"focus_object": "Behind"}), "focus_object"),
            (json!({"aperture_blades": 2}), "aperture_blades"),
            (json!({"aperture_blades": 5.5}), "aperture_blades"),
            (json!({"aperture_rotation": "x"}), "aperture_rotation"),
            (json!({"aperture_ratio": 0}), "aperture_ratio"),
            (json!({"use_dof": "yes"}), "use_dof"),
        ] {
            let s = invalid(extras.clone());
            assert!(s.contains(key), "{extras}: {s}");
            let v = extras.as_object().unwrap().values().next().unwrap();
            let shown = match v {
                Value::Object(_) => v.to_string(),
                _ => v.to_string(),
            };
            assert!(s.contains(&shown), "{extras}: {s}");
        }
    }

    #[test]
    fn invalid_physical_and_cli_values() {
        let e = run(&Case {
            physical: Some(json!({"fStop": 0})),
            ..Case::default()
        })
        .unwrap_err();
        assert!(e.to_string().contains("EXT_camera_physical.fStop"), "{e}");
        let e = run(&Case {
            physical: Some(json!({"sensorSize": [0.036]})),
            ..Case::default()
        })
        .unwrap_err();
        assert!(e.to_string().contains("sensorSize"), "{e}");
        for cli in [
            DofOverrides {
                aperture_fstop: Some(f32::NAN),
                ..Default::default()
            },
            DofOverrides {
                aperture_radius: Some(-1.0),
                ..Default::default()
            },
            DofOverrides {
                focus_distance: Some(0.0),
                ..Default::default()
            },
            DofOverrides {
                focus_object: Some("7".into()),
                ..Default::default()
            },
        ] {
            let e = run(&Case {
                cli: cli.clone(),
                ..Case::default()
            })
            .unwrap_err();
            assert!(e.to_string().contains("command line"), "{cli:?}: {e}");
        }
    }

    #[test]
    fn unknown_keys_and_non_object_extras_are_ignored() {
        let d = run(&Case {
            camera: Some(json!({"colour": "red", "dof": 3})),
            node: Some(json!("just a string")),
            ..Case::default()
        })
        .unwrap();
        assert_eq!(d, run(&Case::default()).unwrap());
    }
}
