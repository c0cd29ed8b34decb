//! The extended material against brute-force integrals of its own value: sampling agrees with
//! evaluation, densities integrate to what sampling accepts, delta lobes carry what they
//! should, and with energy compensation every white combination of lobes conserves energy.

use super::*;
use glam::Vec2;
use std::f32::consts::TAU;

/// Stratified points of the unit square.
fn grid(n: u32) -> impl Iterator<Item = [f32; 2]> {
    (0..n * n).map(move |i| {
        [
            ((i % n) as f32 + 0.5) / n as f32,
            ((i / n) as f32 + 0.5) / n as f32,
        ]
    })
}

/// Uniform directions over the whole sphere (for quadrature), weight 4π / n².
fn sphere(n: u32) -> impl Iterator<Item = Vec3> {
    grid(n).map(|u| {
        let z = 2.0 * u[0] - 1.0;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = TAU * u[1];
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    })
}

fn prepared(mut p: Principled, wo: Vec3, interface: Interface, energy: bool) -> Bsdf {
    p.prepare(&Frame::from_normal(Vec3::Z), wo, interface, energy);
    Bsdf::Principled(Box::new(p))
}

/// Flux albedo by importance sampling: the mean sample weight, transmitted samples through a
/// refractive interface scaled back by η² (the BSDF carries radiance, 1/η² on refraction).
fn albedo_is(b: &Bsdf, wo: Vec3, eta: f32, n: u32) -> Vec3 {
    let mut sum = glam::DVec3::ZERO;
    for (k, u) in grid(n).enumerate() {
        let lobe = ((k as u32).wrapping_mul(2_654_435_761) >> 8) as f32 / (1u32 << 24) as f32;
        if let Some(s) = b.sample(wo, lobe, u) {
            let w = s.weight();
            sum += if s.wi.z < 0.0 { w * eta * eta } else { w }.as_dvec3();
        }
    }
    (sum / (n * n) as f64).as_vec3()
}

/// The same integral by quadrature over the sphere (non-delta lobes only).
fn albedo_quadrature(b: &Bsdf, wo: Vec3, eta: f32) -> Vec3 {
    let n = 800;
    let mut sum = glam::DVec3::ZERO;
    for wi in sphere(n) {
        let f = b.eval(wo, wi).0 * wi.z.abs();
        sum += if wi.z < 0.0 { f * eta * eta } else { f }.as_dvec3();
    }
    (sum * (2.0 * std::f64::consts::TAU) / (n * n) as f64).as_vec3()
}

fn white(roughness: f32) -> Principled {
    Principled::new(Vec3::ONE, 0.0, roughness)
}

#[test]
fn sampling_agrees_with_evaluation() {
    let wo = Vec3::new(0.5, -0.2, 0.6).normalize();
    let mut cases: Vec<(&str, Principled, Interface, f32)> = Vec::new();
    let mut glass = white(0.4);
    glass.transmission = 1.0;
    glass.base = Vec3::new(0.9, 0.8, 0.7);
    cases.push((
        "rough glass",
        glass,
        Interface::Refractive { eta: 1.5 },
        1.5,
    ));
    cases.push((
        "rough glass leaving",
        glass,
        Interface::Refractive { eta: 1.0 / 1.5 },
        1.0 / 1.5,
    ));
    cases.push(("thin rough", glass, Interface::Thin, 1.0));
    let mut layered = Principled::new(Vec3::new(0.7, 0.3, 0.2), 0.3, 0.5);
    layered.sheen = Some(SheenLayer {
        color: Vec3::new(0.5, 0.6, 0.7),
        roughness: 0.4,
    });
    layered.coat = Some(CoatLayer {
        weight: 0.8,
        roughness: 0.3,
        normal: Vec3::new(0.1, 0.05, 1.0).normalize(),
    });
    layered.diffuse_transmission = 0.4;
    layered.diffuse_transmission_color = Vec3::new(0.9, 0.5, 0.2);
    cases.push((
        "coat sheen diffuse transmission",
        layered,
        Interface::Opaque,
        1.0,
    ));
    let mut aniso = Principled::new(Vec3::new(0.9, 0.6, 0.3), 1.0, 0.3);
    aniso.alpha = Vec2::new(0.6, 0.05);
    cases.push(("anisotropic metal", aniso, Interface::Opaque, 1.0));
    let mut film = Principled::new(Vec3::new(0.2, 0.2, 0.2), 0.0, 0.35);
    film.thin_film = Some(ThinFilm {
        factor: 1.0,
        ior: 1.3,
        thickness: 400.0,
    });
    cases.push(("thin film", film, Interface::Opaque, 1.0));
    for energy in [false, true] {
        for (name, p, interface, eta) in &cases {
            let b = prepared(*p, wo, *interface, energy);
            let is = albedo_is(&b, wo, *eta, 300);
            let q = albedo_quadrature(&b, wo, *eta);
            assert!(
                (is - q).abs().max_element() < 0.015,
                "{name} (energy {energy}): sampled {is} vs quadrature {q}"
            );
        }
    }
}

/// The combined density integrates over the sphere to the fraction of samples accepted.
#[test]
fn pdf_integrates_to_the_acceptance_rate() {
    let wo = Vec3::new(0.1, 0.4, 0.5).normalize();
    let mut p = Principled::new(Vec3::splat(0.6), 0.2, 0.6);
    p.transmission = 0.5;
    p.sheen = Some(SheenLayer {
        color: Vec3::splat(0.5),
        roughness: 0.5,
    });
    for interface in [Interface::Thin, Interface::Refractive { eta: 1.4 }] {
        let b = prepared(p, wo, interface, true);
        let m = 256;
        let mut accepted = 0;
        for (k, u) in grid(m).enumerate() {
            let lobe = (k % 97) as f32 / 97.0;
            accepted += usize::from(b.sample(wo, lobe, u).is_some());
        }
        let rate = accepted as f32 / (m * m) as f32;
        let n = 800;
        let total = (sphere(n).map(|wi| b.eval(wo, wi).1 as f64).sum::<f64>()
            * (2.0 * std::f64::consts::TAU)
            / (n * n) as f64) as f32;
        assert!(
            (total - rate).abs() < 0.015,
            "{interface:?}: {total} vs {rate}"
        );
    }
}

/// Ideal glass: reflection with Fresnel's probability, transmission bent by Snell's law,
/// together everything (flux); a thin-walled ideal pane passes straight on.
#[test]
fn ideal_glass_splits_by_fresnel() {
    let wo = Vec3::new(0.6, 0.0, 0.8);
    let mut glass = white(0.0);
    glass.transmission = 1.0;
    let b = prepared(glass, wo, Interface::Refractive { eta: 1.5 }, true);
    let f = fresnel::dielectric(0.8, 1.5);
    let (mut r, mut t, mut flux) = (0usize, 0usize, Vec3::ZERO);
    let n = 2000;
    for k in 0..n {
        let s = b
            .sample(wo, (k as f32 + 0.5) / n as f32, [0.5, 0.5])
            .unwrap();
        let d = s.delta.expect("ideal glass is a delta lobe");
        if s.wi.z > 0.0 {
            r += 1;
            assert!((s.wi - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-6);
            flux += d.weight;
        } else {
            t += 1;
            // Snell: sin θt = sin θi / η.
            assert!((s.wi.x.abs() - 0.6 / 1.5).abs() < 1e-5, "{}", s.wi);
            flux += d.weight * 2.25;
        }
    }
    assert!((r as f32 / n as f32 - f).abs() < 2e-3, "{r} vs Fresnel {f}");
    assert!(t > 0);
    assert!(
        (flux / n as f32 - Vec3::ONE).abs().max_element() < 1e-4,
        "{flux}"
    );
    // Thin-walled: straight through, with glTF's (1 − F) · base colour.
    glass.base = Vec3::new(0.9, 0.5, 0.1);
    let thin = prepared(glass, wo, Interface::Thin, true);
    let want = (1.0 - (0.04 + 0.96 * 0.2f32.powi(5))) * glass.base;
    assert!((thin.straight_transmittance(wo) - want).abs().max_element() < 1e-5);
    let s = thin.sample(wo, 0.999, [0.5, 0.5]).unwrap();
    let d = s.delta.unwrap();
    assert!(d.straight && s.wi == -wo);
}

/// White furnace per lobe combination and roughness: with compensation the directional
/// albedo stays within [0.99, 1.005] for views from grazing to normal; without it the loss is
/// what single scattering loses (reported; 0.31 for a white metal of roughness 1 seen from
/// above).
#[test]
fn white_furnace_conserves_energy_with_compensation() {
    let views = [0.2f32, 0.5, 0.8, 1.0].map(|mu| Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu));
    let mut worst_on = (1.0f32, 1.0f32);
    let mut worst_off = 1.0f32;
    for r in [0.05f32, 0.25, 0.5, 0.75, 1.0] {
        let metal = Principled::new(Vec3::ONE, 1.0, r);
        let dielectric = white(r);
        let mut glass = white(r);
        glass.transmission = 1.0;
        let mut coated = white(r);
        coated.coat = Some(CoatLayer {
            weight: 1.0,
            roughness: r,
            normal: Vec3::Z,
        });
        let mut sheened = white(r);
        sheened.sheen = Some(SheenLayer {
            color: Vec3::ONE,
            roughness: r,
        });
        let mut aniso = Principled::new(Vec3::ONE, 1.0, r);
        aniso.alpha = Vec2::new((r * r + (1.0 - r * r) * 0.64).max(1e-3), r * r);
        let cases = [
            ("metal", metal, Interface::Opaque, 1.0),
            ("dielectric", dielectric, Interface::Opaque, 1.0),
            ("glass", glass, Interface::Refractive { eta: 1.5 }, 1.5),
            (
                "glass leaving",
                glass,
                Interface::Refractive { eta: 1.0 / 1.5 },
                1.0 / 1.5,
            ),
            ("thin", glass, Interface::Thin, 1.0),
            ("coat", coated, Interface::Opaque, 1.0),
            ("sheen", sheened, Interface::Opaque, 1.0),
            ("anisotropic", aniso, Interface::Opaque, 1.0),
        ];
        for (name, p, interface, eta) in cases {
            for wo in views {
                let on = albedo_is(&prepared(p, wo, interface, true), wo, eta, 400).x;
                let off = albedo_is(&prepared(p, wo, interface, false), wo, eta, 400).x;
                println!("{name:<14} r {r:.2} μ {:.1}: on {on:.4} off {off:.4}", wo.z);
                // Leaving glass near total internal reflection little is transmitted, so the
                // tables' interpolation error in that share is amplified: a wider band there
                // (a sphere of it in a furnace stays within the strict one: see the render
                // test).
                let band = if name == "glass leaving" {
                    0.985..=1.015
                } else {
                    0.99..=1.005
                };
                assert!(band.contains(&on), "{name} r {r} μ {}: {on}", wo.z);
                worst_on = (worst_on.0.min(on), worst_on.1.max(on));
                worst_off = worst_off.min(off);
            }
        }
    }
    println!(
        "white furnace: with compensation {:.4}..{:.4}, without it down to {worst_off:.4}",
        worst_on.0, worst_on.1
    );
}

/// What the extended material does without its extensions is the metallic-roughness lobe
/// (Appendix B's single scattering without compensation).
#[test]
fn plain_parameters_match_metal_rough() {
    let wo = Vec3::new(0.3, 0.2, 0.9).normalize();
    let wi = Vec3::new(-0.4, 0.1, 0.8).normalize();
    for (base, m, r) in [(Vec3::new(0.8, 0.4, 0.2), 0.0, 0.5), (Vec3::ONE, 1.0, 0.3)] {
        let p = prepared(Principled::new(base, m, r), wo, Interface::Opaque, false);
        let mr = Bsdf::metal_rough(base, m, r);
        let (a, b) = (p.eval(wo, wi).0, mr.eval(wo, wi).0);
        assert!(
            (a - b).abs().max_element() < 1e-4 * b.max_element(),
            "{a} vs {b}"
        );
    }
}

/// An index-matched boundary (IOR 1 against air, or two media of one IOR) passes light
/// straight on, tinted by the base colour, however rough the surface.
#[test]
fn index_matched_boundary_passes_straight() {
    let wo = Vec3::new(0.3, 0.2, 0.9).normalize();
    let mut glass = white(0.7);
    glass.transmission = 1.0;
    glass.base = Vec3::new(0.5, 0.7, 0.9);
    let b = prepared(glass, wo, Interface::Refractive { eta: 1.0 }, true);
    for k in 0..16 {
        let u = (k as f32 + 0.5) / 16.0;
        let s = b.sample(wo, u, [u, 1.0 - u]).expect("always transmits");
        let d = s.delta.expect("a delta lobe");
        assert!(d.straight && (s.wi + wo).length() < 1e-5, "{}", s.wi);
        assert!(
            (d.weight - glass.base).abs().max_element() < 1e-5,
            "{}",
            d.weight
        );
    }
}
