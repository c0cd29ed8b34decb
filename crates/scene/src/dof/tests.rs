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
            base_dir: std::path::Path::new("."),
            images: &Default::default(),
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
        DofOverrides {
            vignetting: Some(1.5),
            ..Default::default()
        },
        DofOverrides {
            distortion: Some([0.1, f32::INFINITY, 0.0, 0.0, 0.0]),
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

#[test]
fn lens_options_default_to_the_ideal_thin_lens() {
    let d = run(&Case::default()).unwrap();
    assert_eq!(d.lens_options, LensOptions::default());
    assert!(d.lens_options.distortion.is_zero());
}

#[test]
fn lens_options_are_read_key_by_key_the_node_winning() {
    let c = Case {
        camera: Some(json!({"aperture_vignetting": 0.4, "distortion_k1": -0.2,
                            "distortion_p2": 0.01})),
        node: Some(json!({"aperture_vignetting": 0.7, "distortion_k2": 0.05})),
        ..Case::default()
    };
    let o = run(&c).unwrap().lens_options;
    assert_eq!(o.vignetting, 0.7);
    let d = o.distortion;
    assert_eq!((d.k1, d.k2, d.k3, d.p1, d.p2), (-0.2, 0.05, 0.0, 0.0, 0.01));
}

#[test]
fn invalid_lens_options_name_camera_key_and_value() {
    for (extras, key) in [
        (
            json!({"aperture_vignetting": -0.1}),
            "cameras.extras.aperture_vignetting",
        ),
        (
            json!({"aperture_vignetting": 1.5}),
            "cameras.extras.aperture_vignetting",
        ),
        (
            json!({"aperture_vignetting": "x"}),
            "cameras.extras.aperture_vignetting",
        ),
        (
            json!({"distortion_k1": "x"}),
            "cameras.extras.distortion_k1",
        ),
        (
            json!({"distortion_k3": 1e300}),
            "cameras.extras.distortion_k3",
        ),
        (
            json!({"distortion_p1": null}),
            "cameras.extras.distortion_p1",
        ),
    ] {
        let s = invalid(extras.clone());
        assert!(s.contains(key), "{extras}: {s}");
    }
}

#[test]
fn command_line_lens_options_win_over_the_file() {
    let c = Case {
        camera: Some(json!({"aperture_vignetting": 0.4, "distortion_k1": -0.2,
                            "distortion_p2": 0.01})),
        cli: DofOverrides {
            vignetting: Some(0.0),
            distortion: Some([0.1, 0.0, 0.0, 0.0, 0.0]),
            ..Default::default()
        },
        ..Case::default()
    };
    let o = run(&c).unwrap().lens_options;
    assert_eq!(o.vignetting, 0.0);
    let d = o.distortion;
    // The command line gives all five: the file's p2 is replaced by 0.
    assert_eq!((d.k1, d.k2, d.k3, d.p1, d.p2), (0.1, 0.0, 0.0, 0.0, 0.0));
    // Vignetting alone leaves the file's distortion.
    let c = Case {
        cli: DofOverrides {
            vignetting: Some(0.3),
            ..Default::default()
        },
        ..c
    };
    let o = run(&c).unwrap().lens_options;
    assert_eq!(o.vignetting, 0.3);
    assert_eq!(o.distortion.k1, -0.2);
}
