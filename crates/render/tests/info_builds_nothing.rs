//! `aperture info`'s report builds no BVH and decodes no texture (issue 59): it loads the scene
//! as `info` does and counts the process's BVH builds and texture decodes around it.

use aperture_scene::{Animated, LoadOptions};
use aperture_shading::Convention;
use std::path::Path;

// One test in this binary: the counters are the process's.
#[test]
fn the_report_builds_no_bvh_and_decodes_no_texels() {
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.glb");
    let (builds, decodes) = (aperture_accel::builds(), aperture_scene::texture_decodes());
    let options = LoadOptions {
        skip_textures: true,
        ..LoadOptions::default()
    };
    let animated = Animated::load(&demo, &options).unwrap();
    let scene = animated.scene_at(None).unwrap();
    let r = aperture_render::info::report(&scene, Convention::Auto, Convention::Auto);
    let overrides = aperture_render::motion::MotionOverrides::default();
    let motion =
        aperture_render::info::motion::motion_json(&overrides, &animated, &scene, (None, 24.0));
    assert!(motion.is_ok());
    assert_eq!(aperture_accel::builds(), builds, "the report built a BVH");
    assert_eq!(aperture_scene::texture_decodes(), decodes);
    // Its degenerate count is the build's.
    let built = aperture_render::build_accel(&scene, aperture_accel::BvhQuality::Fast);
    assert_eq!(aperture_accel::builds(), builds + 1);
    let degenerate = built.stats().degenerate_triangles as u64;
    assert_eq!(r["triangles"]["degenerate"], degenerate);
    assert!(r["triangles"]["unique"].as_u64().unwrap() > 0);
}
