//! Alpha on shadow rays: a masked leaf casts a leaf-shaped shadow, a blended one a partial
//! shadow in proportion to its coverage.

use aperture_render::{FilterKind, RenderOptions};
use aperture_scene::{
    AlphaMode, Camera, ColorSpace, Dof, Filter, Light, LightKind, Material, Projection, Sampler,
    Scene, Texels, Texture, TextureRef, Wrap,
};
use aperture_shading::{test_scenes, MaterialOverride};
use glam::{Affine3A, Vec3};

/// A white ground at y = 0 and, above it at y = 1, a 1 × 1 occluder whose texture's alpha is
/// `left` for u < 0.5 and `right` beyond. The sun travels along (−1, −1, 0), so the occluder's
/// shadow falls one unit to its left (−X), where an orthographic camera looks straight down at
/// it without seeing the occluder itself.
fn shadow_scene(alpha_mode: AlphaMode, left: u8, right: u8) -> Scene {
    let camera = Camera {
        name: "down".into(),
        node: None,
        index: None,
        // Looking down −Y: the camera's −Z is world −Y, its +Y (image up) world −Z.
        world_from_camera: Affine3A::from_translation(Vec3::new(-1.0, 5.0, 0.0))
            * Affine3A::from_rotation_x(-std::f32::consts::FRAC_PI_2),
        projection: Projection::Orthographic {
            xmag: 0.5,
            ymag: 0.5,
        },
        dof: Dof::default(),
    };
    let occluder = Material {
        base_color_texture: Some(TextureRef {
            texture: 0,
            tex_coord: 0,
            transform: None,
        }),
        metallic_factor: 0.0,
        alpha_mode,
        ..Material::default()
    };
    let mut s = test_scenes::scene(
        vec![
            (test_scenes::quad(20.0, 0), Affine3A::IDENTITY),
            (
                test_scenes::quad(1.0, 1),
                Affine3A::from_translation(Vec3::new(0.0, 1.0, 0.0)),
            ),
        ],
        vec![test_scenes::matte(Vec3::ONE), occluder],
        camera,
    );
    s.textures.push(Texture {
        name: Some("leaf".into()),
        width: 2,
        height: 1,
        texels: Texels::Rgba8(vec![[0, 200, 0, left], [0, 200, 0, right]]),
        color_space: ColorSpace::Srgb,
        sampler: Sampler {
            wrap_u: Wrap::ClampToEdge,
            wrap_v: Wrap::ClampToEdge,
            mag_filter: Filter::Nearest,
        },
    });
    s.lights.push(Light {
        name: None,
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        direction: Vec3::new(-1.0, -1.0, 0.0).normalize(),
        intensity: Vec3::splat(3.0),
    });
    s
}

/// Mean red of the left and right thirds of the image (the shadows of the occluder's two
/// halves).
fn halves(scene: &Scene) -> (f32, f32) {
    let opts = RenderOptions {
        width: 24,
        height: 24,
        spp: 64,
        max_bounces: 0,
        filter: FilterKind::Box,
        // Lambertian ground of albedo 1, so the lit value is exact; alpha is still the
        // material's.
        material_override: MaterialOverride::Diffuse,
        ..RenderOptions::default()
    };
    let film = aperture_tests::render_checked(scene, &opts);
    let mean = |xs: std::ops::Range<u32>| {
        let mut sum = 0.0;
        let mut n = 0;
        for y in 4..20 {
            for x in xs.clone() {
                sum += film.pixel(x, y)[0];
                n += 1;
            }
        }
        sum / n as f32
    };
    (mean(1..8), mean(16..23))
}

#[test]
fn masked_leaf_casts_a_leaf_shaped_shadow() {
    // Left half cut away (alpha 0.2 < 0.5), right half kept (alpha 0.8).
    let (lit, shadowed) = halves(&shadow_scene(AlphaMode::Mask { cutoff: 0.5 }, 51, 204));
    // Ground: albedo 1 under 3 W/m² at 45°: L = 3 cos 45° / π.
    let want = 3.0 * std::f32::consts::FRAC_1_SQRT_2 / std::f32::consts::PI;
    println!("mask: lit {lit} (want {want}), shadowed {shadowed}");
    assert!((lit - want).abs() < 0.01 * want, "{lit} vs {want}");
    assert!(shadowed < 1e-4, "{shadowed}");
    // With the cutoff above both alphas, the whole occluder is cut: no shadow anywhere.
    let (a, b) = halves(&shadow_scene(AlphaMode::Mask { cutoff: 0.9 }, 51, 204));
    assert!((a - want).abs() < 0.01 * want && (b - want).abs() < 0.01 * want);
    // Opaque ignores alpha: shadow everywhere.
    let (a, b) = halves(&shadow_scene(AlphaMode::Opaque, 51, 204));
    assert!(a < 1e-4 && b < 1e-4, "{a} {b}");
}

#[test]
fn blended_leaf_casts_a_partial_shadow() {
    // Coverage 0.25 on the left, 1 on the right.
    let (partial, full) = halves(&shadow_scene(AlphaMode::Blend, 64, 255));
    let want = 3.0 * std::f32::consts::FRAC_1_SQRT_2 / std::f32::consts::PI;
    let expected = want * (1.0 - 64.0 / 255.0);
    println!("blend: partial {partial} (want {expected}), full {full}");
    assert!(
        (partial - expected).abs() < 0.01 * want,
        "{partial} vs {expected}"
    );
    assert!(full < 1e-4, "{full}");
}
