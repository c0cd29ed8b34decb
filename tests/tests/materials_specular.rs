//! `KHR_materials_ior` and `KHR_materials_specular` end to end, textures included: they change
//! only the dielectric Fresnel layer.

use aperture_render::{FilterKind, RenderOptions};
use aperture_scene::{
    Camera, ColorSpace, Dof, Filter, Material, Projection, Sampler, Scene, Texels, Texture,
    TextureRef, Wrap,
};
use aperture_shading::{test_scenes, Environment};
use glam::{Affine3A, Vec3, Vec4};

fn one_texel(rgba: [u8; 4], color_space: ColorSpace) -> Texture {
    Texture {
        name: None,
        width: 1,
        height: 1,
        texels: Texels::Rgba8(vec![rgba]),
        color_space,
        sampler: Sampler {
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::Repeat,
            mag_filter: Filter::Nearest,
        },
    }
}

/// A black dielectric quad facing an orthographic camera under a white sky: all it shows is
/// its specular reflection.
fn quad(material: Material, textures: Vec<Texture>) -> Scene {
    let cam = Camera {
        name: "ortho".into(),
        node: None,
        index: None,
        world_from_camera: Affine3A::from_translation(Vec3::new(0.0, 0.0, 5.0)),
        projection: Projection::Orthographic {
            xmag: 0.4,
            ymag: 0.4,
        },
        dof: Dof::default(),
    };
    let mut s = test_scenes::scene(
        vec![(
            test_scenes::quad(1.0, 0),
            Affine3A::from_rotation_x(std::f32::consts::FRAC_PI_2),
        )],
        vec![material],
        cam,
    );
    s.textures = textures;
    s
}

fn mean(scene: &Scene) -> Vec3 {
    let opts = RenderOptions {
        width: 8,
        height: 8,
        spp: 64,
        max_bounces: 0,
        filter: FilterKind::Box,
        env: Environment::Constant(Vec3::ONE),
        ..RenderOptions::default()
    };
    let film = aperture_tests::render_checked(scene, &opts);
    film.to_rgba()
        .iter()
        .fold(Vec3::ZERO, |s, p| s + Vec3::new(p[0], p[1], p[2]))
        / 64.0
}

fn black_dielectric() -> Material {
    Material {
        base_color_factor: Vec4::new(0.0, 0.0, 0.0, 1.0),
        metallic_factor: 0.0,
        roughness_factor: 0.3,
        ..Material::default()
    }
}

#[test]
fn ior_specular_and_their_textures_set_the_reflection() {
    let tex = |i| {
        Some(TextureRef {
            texture: i,
            tex_coord: 0,
            transform: None,
        })
    };
    let default = mean(&quad(black_dielectric(), vec![]));
    let high_ior = mean(&quad(
        Material {
            ior: 2.0,
            ..black_dielectric()
        },
        vec![],
    ));
    // Specular texture alpha 0: no specular layer at all.
    let off = mean(&quad(
        Material {
            specular_texture: tex(0),
            ..black_dielectric()
        },
        vec![one_texel([255, 255, 255, 0], ColorSpace::Linear)],
    ));
    // Specular colour texture red: a red reflection.
    let red = mean(&quad(
        Material {
            specular_color_texture: tex(0),
            ..black_dielectric()
        },
        vec![one_texel([255, 0, 0, 255], ColorSpace::Srgb)],
    ));
    println!("default {default}, ior 2 {high_ior}, specular 0 {off}, red {red}");
    // F0 = 0.04 at IOR 1.5, 1/9 at IOR 2: the reflection of a white sky grows with it.
    assert!(
        default.x > 0.02 && high_ior.x > 1.8 * default.x,
        "{default} {high_ior}"
    );
    assert!(off.max_element() < 1e-6, "{off}");
    assert!(red.x > 0.5 * default.x && red.y < 0.5 * red.x, "{red}");
}
