//! Issue 45's acceptance for denoising (Open Image Denoise through `aperture-denoise`): the
//! denoised demo at 16 spp is closer to a converged reference than the raw demo at 64 spp, and
//! a defocused highlight keeps its circle of confusion. Without the library the tests skip
//! with a message, except under `CI=true` (CI installs it with `tools/oidn/install.sh`), where
//! they fail.

use aperture_denoise::Denoiser;
use aperture_imageio::Image;
use aperture_render::{FilterKind, Pass, PassSet, RenderOptions};
use aperture_scene::{Dof, Scene};
use aperture_shading::test_scenes;
use aperture_tests::{demo, render_checked};

fn denoiser() -> Option<Denoiser> {
    match Denoiser::load(None) {
        Ok(d) => Some(d),
        Err(e) if std::env::var("CI").as_deref() != Ok("true") => {
            eprintln!("skipping: {e}");
            None
        }
        Err(e) => panic!("CI=true and no OIDN (tools/oidn/install.sh runs first): {e}"),
    }
}

fn aux_passes() -> PassSet {
    PassSet::NONE
        .with(Pass::DenoisingAlbedo)
        .with(Pass::DenoisingNormal)
}

/// `scene` rendered with `opts` as the image an EXR would hold (beauty and passes).
fn image(scene: &Scene, opts: &RenderOptions) -> Image {
    let film = render_checked(scene, opts);
    aperture_output::film_to_image(&film, scene, opts, false, 0.0).expect("image")
}

fn denoised(scene: &Scene, opts: &RenderOptions, d: &Denoiser) -> Image {
    let mut img = image(scene, opts);
    aperture_output::denoised::denoise_image(&mut img, d).expect("denoises");
    img
}

/// The beauty alone, for the metrics (which compare every layer of equal images).
fn beauty(img: &Image) -> Image {
    let mut b = Image::new(img.width, img.height);
    b.rgba = img.rgba.clone();
    b
}

/// The image as the PNG's standard view shows it before its transfer curve: linear, clipped
/// to [0, 1].
fn displayed(img: &Image) -> Image {
    let mut out = beauty(img);
    for p in &mut out.rgba {
        for v in &mut p[..3] {
            *v = v.clamp(0.0, 1.0);
        }
    }
    out
}

/// Issue 45's acceptance, at a size a debug test affords on two cores: the demo at 320×180,
/// a 1024-spp reference with another seed (its own noise adds the same variance to every
/// error below, so it cannot change their order). The error is measured on the displayed image
/// (RMSE of the linear values clipped to [0, 1], what the PNG shows) and as relative MSE on
/// the HDR values. The plain HDR RMSE is printed, not asserted: it is dominated by a few
/// hundred bokeh highlights of radiance up to ~75, where the reference is noisy itself and
/// the denoiser smooths the small hexagons (at 160×90 neither metric is won: the objects are
/// a few pixels across).
#[test]
fn the_denoised_demo_at_16_spp_beats_the_raw_demo_at_64() {
    let Some(d) = denoiser() else { return };
    let scene = aperture_scene::load(&demo::asset_path(), &Default::default()).expect("demo");
    let opts = |spp, seed, passes| RenderOptions {
        width: 320,
        height: 180,
        spp,
        seed,
        passes,
        ..RenderOptions::default()
    };
    let reference = beauty(&image(&scene, &opts(1024, 99, PassSet::NONE)));
    let raw64 = beauty(&image(&scene, &opts(64, 1, PassSet::NONE)));
    let den16 = denoised(&scene, &opts(16, 1, aux_passes().with(Pass::Depth)), &d);
    let depth = den16.layer("Depth").expect("depth").data.clone();
    let raw16 = beauty_of(
        den16.layer("Noisy Image").expect("noisy beauty kept"),
        &den16,
    );
    let den16 = beauty(&den16);
    let shown = displayed(&reference);
    let rmse = |a: &Image| aperture_imageio::metrics::rmse(&displayed(a), &shown).unwrap();
    let rel = |a: &Image| aperture_imageio::metrics::relative_mse(a, &reference).unwrap();
    let hdr = |a: &Image| aperture_imageio::metrics::rmse(a, &reference).unwrap();
    println!(
        "against 1024 spp: displayed RMSE raw 16 spp {:.5}, raw 64 spp {:.5}, denoised 16 spp {:.5}; \
         relative MSE {:.5}, {:.5}, {:.5}; HDR RMSE {:.5}, {:.5}, {:.5}",
        rmse(&raw16),
        rmse(&raw64),
        rmse(&den16),
        rel(&raw16),
        rel(&raw64),
        rel(&den16),
        hdr(&raw16),
        hdr(&raw64),
        hdr(&den16),
    );
    assert!(rmse(&den16) < rmse(&raw64), "displayed RMSE");
    assert!(rel(&den16) < rel(&raw64), "relative MSE");
    assert!(rmse(&raw64) < rmse(&raw16), "more samples, less error");
    in_focus_texture_stays_sharp(&scene, &depth, &reference, &den16, &raw64);
}

/// Mean luminance gradient (|dx| + |dy| of the displayed image) over the pixels whose circle of
/// confusion is under half a pixel, and whose neighbours' are too: the sharp checkerboard and
/// objects at the focus distance.
fn sharpness(img: &Image, mask: &[bool]) -> f64 {
    let w = img.width as usize;
    let lum = |i: usize| {
        let p = img.rgba[i];
        0.2126 * f64::from(p[0].clamp(0.0, 1.0))
            + 0.7152 * f64::from(p[1].clamp(0.0, 1.0))
            + 0.0722 * f64::from(p[2].clamp(0.0, 1.0))
    };
    let inside: Vec<usize> = (0..mask.len()).filter(|i| mask[*i]).collect();
    let sum: f64 = inside
        .iter()
        .map(|&i| (lum(i + 1) - lum(i)).abs() + (lum(i + w) - lum(i)).abs())
        .sum();
    sum / inside.len().max(1) as f64
}

/// Denoising keeps the in-focus texture: there the denoised 16 spp is closer to the reference
/// than raw 64 spp, and its gradient keeps at least 75 % of the reference's (blurring the
/// checkerboard lowers it; the reference's leftover noise raises its own a little).
fn in_focus_texture_stays_sharp(
    scene: &Scene,
    depth: &[f32],
    reference: &Image,
    den: &Image,
    raw64: &Image,
) {
    let (w, h) = (reference.width as usize, reference.height as usize);
    let cam = aperture_render::Camera::new(&scene.cameras[0], w as u32, h as u32);
    let sharp = |i: usize| depth[i] < 1e9 && cam.coc_pixels(depth[i]) < 0.5;
    let mask: Vec<bool> = (0..w * h)
        .map(|i| i % w + 1 < w && i / w + 1 < h && sharp(i) && sharp(i + 1) && sharp(i + w))
        .collect();
    let count = mask.iter().filter(|m| **m).count();
    let (g_ref, g_den) = (sharpness(reference, &mask), sharpness(den, &mask));
    let g64 = sharpness(raw64, &mask);
    let err = |a: &Image| {
        let s: f64 = (0..w * h)
            .filter(|i| mask[*i])
            .flat_map(|i| (0..3).map(move |c| (i, c)))
            .map(|(i, c)| {
                let d = a.rgba[i][c].clamp(0.0, 1.0) - reference.rgba[i][c].clamp(0.0, 1.0);
                f64::from(d * d)
            })
            .sum();
        (s / (3 * count) as f64).sqrt()
    };
    let (e64, e_den) = (err(raw64), err(den));
    println!(
        "in focus ({count} pixels): gradient reference {g_ref:.5}, raw 64 spp {g64:.5}, \
         denoised 16 spp {g_den:.5}; displayed RMSE there raw 64 {e64:.5}, denoised 16 {e_den:.5}"
    );
    assert!(
        count > 500,
        "the demo has an in-focus region: {count} pixels"
    );
    assert!(
        e_den < e64,
        "in focus, denoised 16 spp is closer than raw 64 spp"
    );
    // Measured: 82 % at 320x180, where a checker square is a few pixels: the denoiser softens
    // the finest texture somewhat (noted as open in issue 45).
    assert!(
        g_den > 0.75 * g_ref,
        "in-focus texture blurred: {g_den} vs {g_ref}"
    );
}

/// The `Noisy Image` layer as an image of its own.
fn beauty_of(noisy: &aperture_imageio::Layer, like: &Image) -> Image {
    let mut b = Image::new(like.width, like.height);
    for (p, v) in b.rgba.iter_mut().zip(noisy.data.chunks_exact(4)) {
        p.copy_from_slice(v);
    }
    b
}

/// Diameter of a defocused emitter's disc from its second moment about its centroid (see
/// `render_camera.rs`: E[r²] = c²/8 for a uniform disc of diameter c, plus the emitter's image
/// and the pixel-centre sampling).
fn disc_diameter(img: &Image, emitter_px: f64) -> f64 {
    let w = img.width as usize;
    let at = |i: usize| (((i % w) as f64 + 0.5), ((i / w) as f64 + 0.5));
    let v = |i: usize| f64::from(img.rgba[i][0]).max(0.0);
    let total: f64 = (0..img.rgba.len()).map(v).sum();
    let cx = (0..img.rgba.len()).map(|i| v(i) * at(i).0).sum::<f64>() / total;
    let cy = (0..img.rgba.len()).map(|i| v(i) * at(i).1).sum::<f64>() / total;
    let m2 = (0..img.rgba.len())
        .map(|i| v(i) * ((at(i).0 - cx).powi(2) + (at(i).1 - cy).powi(2)))
        .sum::<f64>()
        / total;
    (8.0 * (m2 + 1.0 / 6.0 - emitter_px * emitter_px / 6.0)).sqrt()
}

#[test]
fn denoising_keeps_the_circle_of_confusion_of_a_defocused_highlight() {
    let Some(d) = denoiser() else { return };
    const SIZE: u32 = 64;
    let (f, z, radius, size) = (2.0f32, 4.0f32, 0.75f32, 0.25f32);
    let dof = Dof {
        enabled: true,
        aperture_radius: radius,
        focus_distance: f,
        ..Dof::default()
    };
    let yfov = 2.0 * 0.5f32.atan();
    let scene = test_scenes::bokeh(size, z, yfov, dof, 50.0);
    let opts = |spp, passes| RenderOptions {
        width: SIZE,
        height: SIZE,
        spp,
        seed: 7,
        max_bounces: 0,
        filter: FilterKind::Box,
        passes,
        ..RenderOptions::default()
    };
    let emitter_px = f64::from(size * SIZE as f32 / (2.0 * z * 0.5));
    let reference = disc_diameter(&image(&scene, &opts(256, PassSet::NONE)), emitter_px);
    let den = denoised(&scene, &opts(16, aux_passes()), &d);
    let c = disc_diameter(&den, emitter_px);
    let err = (c - reference).abs() / reference;
    println!(
        "CoC: undenoised 256 spp {reference:.3} px, denoised 16 spp {c:.3} px, {:.2} %",
        100.0 * err
    );
    assert!(err < 0.03, "denoised {c} px vs {reference} px");
    // Alpha is the render's coverage, untouched.
    let noisy = den.layer("Noisy Image").unwrap();
    for (p, n) in den.rgba.iter().zip(noisy.data.chunks_exact(4)) {
        assert_eq!(p[3].to_bits(), n[3].to_bits());
    }
}
