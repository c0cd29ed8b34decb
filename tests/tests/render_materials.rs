//! Material inputs end to end: base colour factor × vertex colour × sRGB texture, texture
//! orientation (uv (0,0) is the image's top-left), unlit, the diffuse override, the orthographic
//! camera, and alpha masks.

use aperture_render::{build_accel, render, FilterKind, RenderOptions};
use aperture_scene::{
    AlphaMode, Camera, ColorSpace, Dof, Filter, Light, LightKind, Material, Projection, Sampler,
    Scene, Texels, Texture, TextureRef, Wrap,
};
use aperture_shading::{srgb_to_linear, test_scenes, MaterialOverride};
use glam::{Affine3A, Vec3, Vec4};

/// A 2 × 2 texture: red, green / blue, white (rows top to bottom), nearest, clamped.
fn checker() -> Texture {
    Texture {
        name: Some("checker".into()),
        width: 2,
        height: 2,
        texels: Texels::Rgba8(vec![
            [200, 0, 0, 255],
            [0, 200, 0, 255],
            [0, 0, 200, 255],
            [100, 100, 100, 255],
        ]),
        color_space: ColorSpace::Srgb,
        sampler: Sampler {
            wrap_u: Wrap::ClampToEdge,
            wrap_v: Wrap::ClampToEdge,
            mag_filter: Filter::Nearest,
        },
    }
}

/// A unit quad facing +Z at the origin (uv (0,0) at its top-left), filling an orthographic
/// camera's view.
fn textured_quad(material: Material) -> Scene {
    let cam = Camera {
        name: "ortho".into(),
        node: None,
        index: None,
        world_from_camera: Affine3A::from_translation(Vec3::new(0.0, 0.0, 5.0)),
        projection: Projection::Orthographic {
            xmag: 0.5,
            ymag: 0.5,
        },
        dof: Dof::default(),
    };
    let mut quad = test_scenes::quad(1.0, 0);
    quad.colors = vec![Vec4::new(1.0, 0.5, 1.0, 1.0); 4];
    let mut s = test_scenes::scene(
        vec![(quad, Affine3A::from_rotation_x(std::f32::consts::FRAC_PI_2))],
        vec![material],
        cam,
    );
    s.textures.push(checker());
    s
}

fn textured_material(unlit: bool) -> Material {
    Material {
        base_color_factor: Vec4::new(1.0, 1.0, 0.5, 1.0),
        base_color_texture: Some(TextureRef {
            texture: 0,
            tex_coord: 0,
            transform: None,
        }),
        metallic_factor: 0.0,
        unlit,
        ..Material::default()
    }
}

fn opts() -> RenderOptions {
    RenderOptions {
        width: 16,
        height: 16,
        spp: 4,
        filter: FilterKind::Box,
        max_bounces: 0,
        ..RenderOptions::default()
    }
}

/// Expected base colour of each quadrant: texel (decoded) × factor × vertex colour.
fn expected(quadrant: usize) -> Vec3 {
    let texel = [[200u8, 0, 0], [0, 200, 0], [0, 0, 200], [100, 100, 100]][quadrant];
    let t = Vec3::from_array(texel.map(|c| srgb_to_linear(c as f32 / 255.0)));
    t * Vec3::new(1.0, 1.0, 0.5) * Vec3::new(1.0, 0.5, 1.0)
}

/// Each quadrant's pixel centre, away from the edges ((x, y), row 0 at the top), shows
/// [`expected`] exactly, fully covered.
fn assert_unlit_quadrants(film: &aperture_render::Film) {
    for (q, (x, y)) in [(0, (3, 3)), (1, (12, 3)), (2, (3, 12)), (3, (12, 12))] {
        let p = film.pixel(x, y);
        let want = expected(q);
        assert!(
            (Vec3::new(p[0], p[1], p[2]) - want).abs().max_element() < 1e-5,
            "quadrant {q}: {p:?} vs {want}"
        );
        assert_eq!(p[3], 1.0);
    }
}

#[test]
fn unlit_shows_base_colour_times_vertex_colour_times_texture() {
    let scene = textured_quad(textured_material(true));
    let film = aperture_tests::render_checked(&scene, &opts());
    assert_unlit_quadrants(&film);
}

#[test]
fn diffuse_override_is_lambertian_of_the_base_colour() {
    let mut scene = textured_quad(Material {
        metallic_factor: 1.0,
        roughness_factor: 0.1,
        ..textured_material(false)
    });
    scene.lights.push(Light {
        name: None,
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        direction: Vec3::NEG_Z,
        intensity: Vec3::splat(3.0),
    });
    let accel = build_accel(&scene, Default::default());
    let clay = RenderOptions {
        material_override: MaterialOverride::Diffuse,
        ..opts()
    };
    let film = render(&scene, &accel, &clay, &|_, _| {}).unwrap();
    assert_eq!(film.dropped_samples(), 0);
    for (q, (x, y)) in [(0, (3, 3)), (3, (12, 12))] {
        let p = film.pixel(x, y);
        let want = expected(q) / std::f32::consts::PI * 3.0;
        assert!(
            (Vec3::new(p[0], p[1], p[2]) - want).abs().max_element() < 1e-4,
            "quadrant {q}: {p:?} vs {want}"
        );
    }
    // Without the override the polished metal reflects the head-on light very differently.
    let film = render(&scene, &accel, &opts(), &|_, _| {}).unwrap();
    assert_eq!(film.dropped_samples(), 0);
    let p = film.pixel(3, 3);
    let clay_value = expected(0).x / std::f32::consts::PI * 3.0;
    assert!((p[0] - clay_value).abs() > 0.1 * clay_value, "{p:?}");
}

#[test]
fn alpha_mask_cuts_holes() {
    let mut m = textured_material(true);
    m.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    let mut scene = textured_quad(m);
    if let Texels::Rgba8(t) = &mut scene.textures[0].texels {
        t[1][3] = 0; // top-right texel transparent
    }
    let film = aperture_tests::render_checked(&scene, &opts());
    assert_eq!(film.pixel(12, 3)[3], 0.0, "cut out");
    assert_eq!(film.pixel(3, 3)[3], 1.0, "kept");
}

/// Any `TEXCOORD_n`: a texture that reads set 2 (here the quad's real coordinates, while sets 0
/// and 1 are all zero) shows its four quadrants as set 0 would.
#[test]
fn a_texture_may_read_any_texcoord_set() {
    let mut material = textured_material(true);
    if let Some(t) = &mut material.base_color_texture {
        t.tex_coord = 2;
    }
    let mut scene = textured_quad(material);
    let mesh = std::sync::Arc::make_mut(&mut scene.meshes[0]);
    mesh.uv_more = vec![std::mem::take(&mut mesh.uv0)];
    mesh.uv0 = vec![glam::Vec2::ZERO; 4];
    mesh.uv1 = vec![glam::Vec2::ZERO; 4];
    let film = aperture_tests::render_checked(&scene, &opts());
    assert_unlit_quadrants(&film);
}
