use super::*;
use crate::background::PixelRect;
use crate::filter::FilterKind;
use aperture_scene::{Dof, Projection};

/// A sample as drawn: its stream and camera ray, if any.
type Drawn = (SampleStream, Option<CameraRay>);

fn cameras() -> Vec<Camera> {
    let mut out = Vec::new();
    for ortho in [false, true] {
        for (radius, blades) in [(0.0, 0), (0.1, 0), (0.2, 6)] {
            let mut sc = crate::camera::test_scene_camera(Dof {
                enabled: true,
                aperture_radius: radius,
                focus_distance: 4.0,
                blades,
                rotation: 0.2,
                ratio: 1.3,
                ..Dof::default()
            });
            if ortho {
                sc.projection = Projection::Orthographic {
                    xmag: 2.0,
                    ymag: 1.5,
                };
            }
            out.push(Camera::new(&sc, 24, 16));
        }
    }
    out
}

/// The bits of a sample's camera dimensions, first bounce and ray, for exact comparison.
fn bits((s, r): Drawn) -> impl PartialEq + std::fmt::Debug {
    let r = r.map(|r| (r.origin.to_array(), r.dir.to_array()));
    (
        s.camera().map(f32::to_bits),
        s.bounce(1).bsdf.map(f32::to_bits),
        r.map(|(o, d)| (o.map(f32::to_bits), d.map(f32::to_bits))),
    )
}

/// Runs of consecutive samples, a pixel revisited, samples skipped and repeated.
fn items() -> Vec<(u32, u32, u32)> {
    let mut items: Vec<(u32, u32, u32)> = (0..3)
        .flat_map(|y| (0..4).flat_map(move |x| (0..5).map(move |i| (x, y, i))))
        .collect();
    items.extend([
        (2, 1, 9),
        (2, 1, 3),
        (2, 1, 3),
        (2, 1, 4),
        (0, 0, 0),
        (23, 15, 7),
    ]);
    items
}

/// One render's primary samples: camera, filter, sequence, seed and sample offset.
struct Setup<'a> {
    camera: &'a Camera,
    filter: &'a Filter,
    kind: SamplerKind,
    seed: u32,
    offset: u32,
}

impl Setup<'_> {
    fn primary(&self) -> PrimarySamples<'_> {
        PrimarySamples::new(self.camera, self.filter, self.kind, self.seed, self.offset)
    }

    /// Each item's sample drawn alone.
    fn want(&self, items: &[(u32, u32, u32)]) -> Vec<Drawn> {
        items
            .iter()
            .map(|&(x, y, i)| {
                drawn_alone(
                    self.camera,
                    self.filter,
                    self.kind,
                    (x, y, self.offset + i, self.seed),
                )
            })
            .collect()
    }
}

/// Calls `f` for every camera, filter, sequence and (seed, offset) pair.
fn for_each_setup(mut f: impl FnMut(&Setup)) {
    for camera in cameras() {
        for filter in [FilterKind::Box, FilterKind::BlackmanHarris] {
            let filter = Filter::new(filter);
            for kind in [SamplerKind::Sobol, SamplerKind::Random] {
                for (seed, offset) in [(0, 0), (77, 64)] {
                    f(&Setup {
                        camera: &camera,
                        filter: &filter,
                        kind,
                        seed,
                        offset,
                    });
                }
            }
        }
    }
}

/// What `fill` gave for a sample that was not left as background: the next traced ray, or no
/// ray (with the stream drawn alone, which `fill` does not keep).
fn filled(
    start: Start,
    traced: &mut std::slice::Iter<crate::integrator::wavefront::CameraStart>,
    want: &Drawn,
) -> Drawn {
    let got = (start == Start::Traced)
        .then(|| traced.next())
        .flatten()
        .map(|s| {
            let ray = CameraRay {
                origin: s.origin,
                dir: s.dir,
            };
            (s.stream, Some(ray))
        });
    got.unwrap_or((want.0, None))
}

#[test]
fn samples_are_those_drawn_alone() {
    let items = items();
    for_each_setup(|setup| {
        let mut primary = setup.primary();
        let want = setup.want(&items);
        for (&(x, y, i), want) in items.iter().zip(&want) {
            let got = primary.sample(x, y, i);
            assert_eq!(bits(got), bits(*want), "({x}, {y}) sample {i}");
        }
    });
}

/// `fill`, by runs of 7 (the lanes' batches cut anywhere): the same samples, those without a ray
/// left out of `starts`.
#[test]
fn filled_samples_are_those_drawn_alone() {
    let items = items();
    for_each_setup(|setup| {
        let want = setup.want(&items);
        let mut primary = setup.primary();
        let mut it = items.iter().enumerate().map(|(k, &(x, y, i))| (k, x, y, i));
        let (mut run, mut starts) = (Vec::new(), Vec::new());
        loop {
            let (had, traced) = (run.len(), starts.len());
            primary.fill(&mut it, 7, &mut run, &mut starts);
            assert!(run.len() - had <= 7 && starts.len() - traced <= run.len() - had);
            if run.len() == had {
                break;
            }
        }
        let mut traced = starts.iter();
        assert_eq!(run.len(), items.len());
        for (&(k, start), want) in run.iter().zip(&want) {
            assert_ne!(start, Start::Background);
            let (x, y, i) = items[k];
            let got = filled(start, &mut traced, want);
            assert_eq!(bits(got), bits(*want), "fill: ({x}, {y}) sample {i}");
        }
        assert!(traced.next().is_none());
    });
}

/// With a set of pixels that see the scene (a rectangle): the others' samples are background, in
/// their places; the rest as drawn alone.
#[test]
fn samples_outside_the_scene_pixels_are_background() {
    let items = items();
    for_each_setup(|setup| {
        let want = setup.want(&items);
        let rect = PixelRect {
            x0: 1,
            x1: 2,
            y0: 0,
            y1: 1,
        };
        let camera = setup.camera;
        let scene = PixelMask::from_rects(camera.width, camera.height, &[rect]);
        let mut primary = setup.primary().with_scene(&scene);
        let mut it = items.iter().enumerate().map(|(k, &(x, y, i))| (k, x, y, i));
        let (mut run, mut starts) = (Vec::new(), Vec::new());
        while it.len() > 0 {
            let traced = starts.len();
            primary.fill(&mut it, 3, &mut run, &mut starts);
            assert!(starts.len() - traced <= 3);
        }
        let mut traced = starts.iter();
        assert_eq!(run.len(), items.len());
        for (n, (&(k, start), want)) in run.iter().zip(&want).enumerate() {
            let (x, y, i) = items[k];
            assert_eq!(k, n, "in order");
            if !scene.contains(x, y) {
                assert_eq!(start, Start::Background, "({x}, {y})");
                continue;
            }
            assert_ne!(start, Start::Background);
            let got = filled(start, &mut traced, want);
            assert_eq!(bits(got), bits(*want), "scene: ({x}, {y}) sample {i}");
        }
        assert!(traced.next().is_none());
    });
}

/// Under chromatic aberration each traced sample carries the channel its stream picks, drawn
/// once by the camera, and its ray is that channel's.
#[test]
fn filled_samples_carry_their_channel() {
    let mut cam = cameras()[2];
    cam.lens.chromatic = Some(crate::lens::Chromatic {
        lateral: 0.05,
        longitudinal: 0.2,
    });
    let filter = Filter::new(FilterKind::Box);
    let mut primary = PrimarySamples::new(&cam, &filter, SamplerKind::Sobol, 3, 0);
    let items = items();
    let mut it = items.iter().enumerate().map(|(k, &(x, y, i))| (k, x, y, i));
    let (mut run, mut starts) = (Vec::new(), Vec::new());
    while it.len() > 0 {
        primary.fill(&mut it, 5, &mut run, &mut starts);
    }
    assert_eq!(starts.len(), items.len());
    let rays = |r: Option<CameraRay>| r.map(|r| (r.origin.to_array(), r.dir.to_array()));
    let mut seen = [0usize; 3];
    for (s, &(k, start)) in starts.iter().zip(run.iter()) {
        assert_eq!(start, Start::Traced);
        let want = crate::lens::channel_of(s.stream.wavelength(0)).0;
        assert_eq!(s.channel, Some(want as u8), "item {k}");
        seen[want] += 1;
        // The sample as drawn alone, its ray made for that channel.
        let (x, y, _) = items[k];
        let c = s.stream.camera();
        let offset = filter.sample([c[0], c[1]]);
        let sample = CameraSample {
            p_film: Vec2::new(x as f32 + 0.5 + offset.x, y as f32 + 0.5 + offset.y),
            p_lens: Vec2::new(c[2], c[3]),
            time: 0.0,
        };
        let got = rays(Some(CameraRay {
            origin: s.origin,
            dir: s.dir,
        }));
        assert_eq!(got, rays(cam.generate_ray_channel(&sample, want)));
        if want != 1 {
            assert_ne!(got, rays(cam.generate_ray(&sample)), "item {k}");
        }
    }
    assert!(seen.iter().all(|&n| n > 3), "{seen:?}");
}
