//! The extended glTF material (SPEC §5, the layering of glTF's PBR "next" model): a GGX clear
//! coat over a Charlie sheen over the base, the base being a conductor (F0 = base colour) mixed
//! by `metallic` with a dielectric whose specular layer (`KHR_materials_ior`/`specular`,
//! possibly anisotropic, possibly under a thin film) covers a mix of Lambertian diffuse,
//! Lambertian diffuse transmission and microfacet specular transmission (Walter et al. 2007).
//!
//! Layers are energy-correct as the extensions say: the coat's Fresnel and the sheen's albedo
//! attenuate what lies below. With energy compensation on, every GGX lobe also gets back what
//! single scattering loses (Turquin 2019, tables in [`super::energy`]) and each layer weights
//! what lies below by one minus its own directional albedo at the view (albedo scaling), so a
//! white furnace stays white; off, the layers follow the extensions' formulas literally.
//!
//! Sampling picks one lobe in proportion to its estimated albedo and combines all non-delta
//! lobes' densities (one-sample MIS). The specular lobe draws one visible normal and chooses
//! reflection or transmission by their weights at that normal. Lobes sharper than
//! [`MIN_ALPHA`] are ideal (delta) lobes: light sampling cannot find them.

use super::common::{Albedos, Frame, LobeSplit};
use super::energy::{
    fresnel_average, ggx_albedo, ggx_albedo_aniso, glass_albedo, ms_factor, multiple_scattering,
    schlick_average, sheen_albedo,
};
use super::fresnel::{dielectric, f0_from_eta, iridescence, schlick};
use super::ggx::{Ggx, MIN_ALPHA};
use glam::{Vec2, Vec3};

mod eval;
mod sample;

/// What the specular layer's transmission does at this surface (decided per hit by the
/// integrator: thin-walled or a refractive boundary between two media).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Interface {
    /// No specular transmission.
    #[default]
    Opaque,
    /// Thin-walled: transmitted light leaves the far side without bending.
    Thin,
    /// A refractive boundary; `eta` = IOR of the far side / IOR of the viewer's side.
    Refractive {
        /// Relative IOR.
        eta: f32,
    },
}

/// `KHR_materials_sheen` at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SheenLayer {
    /// Sheen colour (linear).
    pub color: Vec3,
    /// Perceptual sheen roughness.
    pub roughness: f32,
}

/// `KHR_materials_clearcoat` at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoatLayer {
    /// Coat weight in [0, 1].
    pub weight: f32,
    /// Perceptual coat roughness.
    pub roughness: f32,
    /// The coat's unit normal: world space as shading builds it, in the shading frame (`+Z`
    /// the base's shading normal) after [`Principled::prepare`].
    pub normal: Vec3,
}

/// `KHR_materials_iridescence` at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThinFilm {
    /// Iridescence weight in [0, 1].
    pub factor: f32,
    /// Film IOR.
    pub ior: f32,
    /// Film thickness in nanometres.
    pub thickness: f32,
}

/// The extended material's parameters at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Principled {
    /// Base colour (linear); also tints specular transmission.
    pub base: Vec3,
    /// Metallic in [0, 1].
    pub metallic: f32,
    /// GGX roughness along the frame's x axis and y axis (α, not perceptual).
    pub alpha: Vec2,
    /// The material's IOR (F0 of the opaque and thin-walled specular layer).
    pub ior: f32,
    /// `KHR_materials_specular` weight in [0, 1].
    pub specular: f32,
    /// `KHR_materials_specular` F0 tint.
    pub specular_color: Vec3,
    /// Specular transmission weight in [0, 1].
    pub transmission: f32,
    /// Diffuse transmission weight in [0, 1].
    pub diffuse_transmission: f32,
    /// Diffuse transmission colour.
    pub diffuse_transmission_color: Vec3,
    /// Sheen layer.
    pub sheen: Option<SheenLayer>,
    /// Clear coat layer.
    pub coat: Option<CoatLayer>,
    /// Thin film over the base.
    pub thin_film: Option<ThinFilm>,
    /// Set by [`Principled::prepare`].
    view: View,
}

/// What one view of the material needs, computed once per shading point.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct View {
    interface: Interface,
    ggx: Option<Ggx>,
    /// Tinted dielectric F0 and the untinted one of the interface.
    f0t: Vec3,
    f0e: f32,
    /// Multiple-scattering factors: conductor, dielectric reflection, transmission.
    ms_metal: Vec3,
    ms_r: f32,
    ms_t: f32,
    /// Albedo-scaled weight of the diffuse base (`None`: glTF's per-direction fresnel_mix).
    w_diffuse: Option<f32>,
    /// Reflected and transmitted albedo of the dielectric interface at the view.
    e_r: f32,
    e_t: f32,
    coat: Option<CoatView>,
    /// Sheen albedo at the view.
    sheen_e: f32,
    /// What the coat leaves for the layers below at the view.
    coat_below: f32,
    /// What reaches the base through coat and sheen at the view (albedo scaling; without
    /// energy compensation only the coat's part: the sheen's is per direction).
    below: f32,
    energy: bool,
    /// Cumulative lobe probabilities: coat, sheen, specular, diffuse, diffuse transmission.
    cdf: [f32; 5],
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct CoatView {
    ggx: Ggx,
    frame: Frame,
    wo: Vec3,
    ms: f32,
}

/// Coat reflectance at normal incidence (IOR 1.5).
const COAT_F0: f32 = 0.04;

const COAT: usize = 0;
const SHEEN: usize = 1;
const SPEC: usize = 2;
const DIFFUSE: usize = 3;
const DIFFUSE_T: usize = 4;

impl Principled {
    /// A material with glTF's defaults: white, dielectric, rough, IOR 1.5, nothing else.
    pub fn new(base: Vec3, metallic: f32, roughness: f32) -> Self {
        let a = (roughness.clamp(0.0, 1.0)).powi(2);
        Self {
            base,
            metallic: metallic.clamp(0.0, 1.0),
            alpha: Vec2::splat(a),
            ior: 1.5,
            specular: 1.0,
            specular_color: Vec3::ONE,
            transmission: 0.0,
            diffuse_transmission: 0.0,
            diffuse_transmission_color: Vec3::ONE,
            sheen: None,
            coat: None,
            thin_film: None,
            view: View::default(),
        }
    }

    /// The specular layer's distribution, `None` when it is an ideal mirror.
    fn ggx(&self) -> Option<Ggx> {
        let g = Ggx {
            ax: self.alpha.x.max(MIN_ALPHA),
            ay: self.alpha.y.max(MIN_ALPHA),
        };
        (!Ggx {
            ax: self.alpha.x,
            ay: self.alpha.y,
        }
        .is_delta())
        .then_some(g)
    }

    /// True when some lobe may send light to the far side of the surface.
    pub fn transmits(&self) -> bool {
        (self.transmission > 0.0 || self.diffuse_transmission > 0.0) && self.metallic < 1.0
    }

    /// Computes everything that depends on the view `wo` (local to `frame`, `wo.z > 0`) and
    /// the interface; `energy` switches energy compensation. The coat normal (world) is taken
    /// into `frame`, on the side of its +Z.
    pub fn prepare(&mut self, frame: &Frame, wo: Vec3, interface: Interface, energy: bool) {
        if let Some(c) = &mut self.coat {
            let n = frame.to_local(c.normal);
            c.normal = if n.z < 0.0 { -n } else { n };
        }
        let interface = if self.transmission > 0.0 {
            interface
        } else {
            Interface::Opaque
        };
        // An index-matched boundary (relative IOR 1) neither reflects nor bends, however
        // rough: light crosses it straight (the medium behind it may still absorb).
        let matched =
            matches!(interface, Interface::Refractive { eta } if (eta - 1.0).abs() < 1e-4);
        let mut v = View {
            interface,
            ggx: if matched { None } else { self.ggx() },
            energy,
            ms_metal: Vec3::ONE,
            ms_r: 1.0,
            ms_t: 1.0,
            ..View::default()
        };
        v.f0e = match interface {
            Interface::Refractive { eta } => f0_from_eta(eta),
            _ => ior_f0(self.ior),
        };
        v.f0t = (v.f0e * self.specular_color).min(Vec3::ONE);
        self.view = v;
        self.prepare_specular(wo);
        self.prepare_layers(wo);
        self.prepare_probabilities(wo);
    }

    /// Interface albedos and multiple-scattering factors of the specular layer.
    fn prepare_specular(&mut self, wo: Vec3) {
        let v = &mut self.view;
        let mu = wo.z.clamp(0.0, 1.0);
        match v.ggx {
            None => {
                let fe = match v.interface {
                    Interface::Refractive { eta } => dielectric(mu, eta),
                    _ => schlick(Vec3::splat(v.f0e), mu).x,
                };
                v.e_r = fe;
                v.e_t = 1.0 - fe;
            }
            Some(g) => {
                let (ta, tb) = ggx_albedo_aniso(wo, g.ax, g.ay);
                let a = g.alpha_mean();
                (v.e_r, v.e_t) = match v.interface {
                    Interface::Refractive { eta } => glass_albedo(mu, a, eta),
                    Interface::Thin => (v.f0e * ta + tb, (1.0 - v.f0e) * ta),
                    Interface::Opaque => (v.f0e * ta + tb, 0.0),
                };
                if v.energy {
                    let e1 = ta + tb;
                    v.ms_metal = ms_factor(e1, schlick_average(self.base));
                    let f_avg = match v.interface {
                        Interface::Refractive { eta } => fresnel_average(eta),
                        _ => schlick_average(Vec3::splat(v.f0e)).x,
                    };
                    v.ms_r = ms_factor(e1, Vec3::splat(f_avg)).x;
                    if v.interface != Interface::Opaque && v.e_t > 1e-4 {
                        v.ms_t = ((1.0 - v.e_r * v.ms_r) / v.e_t).clamp(1.0, 16.0);
                    }
                }
            }
        }
        if v.energy {
            let tint = match v.interface {
                Interface::Refractive { .. } => 1.0,
                _ => v.f0t.max_element() / v.f0e.max(1e-6),
            };
            let e = (v.e_r * v.ms_r * tint.max(1.0)).min(1.0);
            v.w_diffuse = Some((1.0 - self.specular * e).max(0.0));
        }
    }

    /// Coat frame and albedo, sheen albedo and what they leave for the base.
    fn prepare_layers(&mut self, wo: Vec3) {
        let energy = self.view.energy;
        let mut coat_below = 1.0;
        self.view.coat = self.coat.filter(|c| c.weight > 0.0).map(|c| {
            let n = super::common::bend_towards(c.normal, wo);
            let frame = Frame::from_normal(n);
            let wo_c = frame.to_local(wo);
            let a = (c.roughness.clamp(0.0, 1.0)).powi(2);
            let delta = Ggx::isotropic(a).is_delta();
            let mu = wo_c.z.clamp(0.0, 1.0);
            let (e, ms) = if delta || !energy {
                (schlick(Vec3::splat(COAT_F0), mu).x, 1.0)
            } else {
                let (ta, tb) = ggx_albedo(mu, a);
                let ms = multiple_scattering(mu, a, schlick_average(Vec3::splat(COAT_F0))).x;
                ((COAT_F0 * ta + tb) * ms, ms)
            };
            coat_below = 1.0 - c.weight * e.min(1.0);
            CoatView {
                ggx: Ggx::isotropic(if delta { 0.0 } else { a.max(MIN_ALPHA) }),
                frame,
                wo: wo_c,
                ms,
            }
        });
        self.view.coat_below = coat_below.max(0.0);
        self.view.below = self.view.coat_below;
        if let Some(s) = self.sheen {
            self.view.sheen_e = sheen_albedo(wo.z, s.roughness);
            if energy {
                self.view.below *= (1.0 - s.color.max_element() * self.view.sheen_e).max(0.0);
            }
        }
    }

    /// Lobe selection probabilities from each lobe's albedo estimate at the view.
    fn prepare_probabilities(&mut self, wo: Vec3) {
        let v = self.view;
        let m = self.metallic;
        let mut a = [0.0f32; 5];
        if let (Some(c), Some(cv)) = (self.coat, v.coat) {
            a[COAT] = c.weight * schlick(Vec3::splat(COAT_F0), cv.wo.z.max(0.0)).x.max(0.05);
        }
        if let Some(s) = self.sheen {
            a[SHEEN] = v.coat_below * s.color.max_element() * v.sheen_e;
        }
        let below = v.below;
        let fd = self.fresnel_dielectric(wo.z).max_element();
        let fm = self.fresnel_metal(wo.z).max_element();
        a[SPEC] = below
            * (m * fm
                + (1.0 - m)
                    * (self.specular * fd
                        + self.transmission
                            * (1.0 - self.specular * fd)
                            * self.base.max_element()));
        let wd = v.w_diffuse.unwrap_or(1.0 - self.specular * fd);
        let dielectric_base = below * (1.0 - m) * (1.0 - self.transmission) * wd;
        a[DIFFUSE] = dielectric_base * (1.0 - self.diffuse_transmission) * self.base.max_element();
        a[DIFFUSE_T] = dielectric_base
            * self.diffuse_transmission
            * self.diffuse_transmission_color.max_element();
        let total: f32 = a.iter().sum();
        let mut cdf = [0.0f32; 5];
        let mut acc = 0.0;
        for (c, x) in cdf.iter_mut().zip(a) {
            acc += if total > 0.0 { x / total } else { 0.0 };
            *c = acc;
        }
        if total > 0.0 {
            cdf[4] = 1.0;
        }
        self.view.cdf = cdf;
    }

    fn probability(&self, lobe: usize) -> f32 {
        let lo = if lobe == 0 {
            0.0
        } else {
            self.view.cdf[lobe - 1]
        };
        self.view.cdf[lobe] - lo
    }

    /// The dielectric specular layer's Fresnel (tinted, with the thin film) at cosine `cos`.
    fn fresnel_dielectric(&self, cos: f32) -> Vec3 {
        let v = &self.view;
        let f = match v.interface {
            Interface::Refractive { eta } => {
                let fe = dielectric(cos, eta);
                let s = if v.f0e < 1.0 {
                    ((fe - v.f0e) / (1.0 - v.f0e)).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                v.f0t + (Vec3::ONE - v.f0t) * s
            }
            _ => schlick(v.f0t, cos),
        };
        self.with_film(f, cos, v.f0t)
    }

    /// The conductor's Fresnel (F0 = base colour, with the thin film) at cosine `cos`.
    fn fresnel_metal(&self, cos: f32) -> Vec3 {
        self.with_film(schlick(self.base, cos), cos, self.base)
    }

    fn with_film(&self, f: Vec3, cos: f32, f0: Vec3) -> Vec3 {
        match self.thin_film {
            Some(t) if t.factor > 0.0 => {
                let outside = if self.view.coat.is_some() { 1.5 } else { 1.0 };
                let fi = iridescence(outside, t.ior, cos, t.thickness, f0);
                f.lerp(fi, t.factor)
            }
            _ => f,
        }
    }

    /// Reflection and transmission weights of the specular layer at a microfacet whose
    /// cosine with the view is `cos`: `(reflected value factor, transmitted value factor,
    /// probability of choosing reflection)`.
    fn spec_weights(&self, cos: f32) -> (Vec3, Vec3, f32) {
        let m = self.metallic;
        let v = &self.view;
        let fm = self.fresnel_metal(cos);
        let fd = self.fresnel_dielectric(cos);
        let r = m * fm * v.ms_metal + (1.0 - m) * self.specular * fd * v.ms_r;
        let t = match v.interface {
            Interface::Opaque => Vec3::ZERO,
            _ => {
                (1.0 - m)
                    * self.transmission
                    * (1.0 - self.specular * fd.max_element())
                    * self.base
                    * v.ms_t
            }
        };
        let (rw, tw) = (r.max_element(), t.max_element());
        let p_r = if rw + tw > 0.0 { rw / (rw + tw) } else { 1.0 };
        (r, t, p_r)
    }

    /// What coat and sheen leave for the base for incident cosine `nl`
    /// (the sheen's part per direction only without energy compensation, as the extension
    /// writes it: the smaller of its albedo scalings at the view and the light).
    fn below(&self, nl: f32) -> f32 {
        let v = &self.view;
        if v.energy {
            return v.below;
        }
        let sheen = match self.sheen {
            Some(s) => {
                let k = s.color.max_element();
                (1.0 - k * v.sheen_e)
                    .min(1.0 - k * sheen_albedo(nl.abs(), s.roughness))
                    .max(0.0)
            }
            None => 1.0,
        };
        v.coat_below * sheen
    }

    /// Each lobe's value (without cosine) and density for `wi`, by lobe index; delta lobes
    /// contribute nothing.
    /// How the value at (`wo`, `wi`) splits between the lobes.
    pub fn lobe_split(&self, wo: Vec3, wi: Vec3) -> LobeSplit {
        let l = self.lobes(wo, wi);
        let (diffuse, glossy, transmission) = if wi.z > 0.0 {
            (l[SHEEN].0 + l[DIFFUSE].0, l[COAT].0 + l[SPEC].0, Vec3::ZERO)
        } else {
            (l[DIFFUSE_T].0, Vec3::ZERO, l[SPEC].0)
        };
        LobeSplit::from_parts(diffuse, glossy, transmission)
    }

    /// Each lobe's directional albedo seen from `wo` (estimates: the Color passes and the
    /// denoising albedo show them; the estimator does not use them).
    pub fn albedos(&self, wo: Vec3) -> Albedos {
        let v = &self.view;
        let m = self.metallic;
        let mu = wo.z.clamp(0.0, 1.0);
        let below = self.below(mu);
        let fd = self.fresnel_dielectric(mu);
        let wd = v
            .w_diffuse
            .unwrap_or(1.0 - self.specular * fd.max_element());
        let dielectric = below * (1.0 - m) * (1.0 - self.transmission) * wd;
        let sheen = self
            .sheen
            .map_or(Vec3::ZERO, |s| v.coat_below * s.color * v.sheen_e);
        let coat = match (self.coat, v.coat) {
            (Some(_), Some(_)) => Vec3::splat(1.0 - v.coat_below),
            _ => Vec3::ZERO,
        };
        let (metal, refl) = match v.ggx {
            None => (self.fresnel_metal(mu), fd),
            Some(g) => {
                let r = g.alpha_mean().sqrt();
                let refl = match v.interface {
                    Interface::Refractive { .. } => Vec3::splat(v.e_r),
                    _ => super::common::env_brdf(v.f0t, r, mu),
                };
                (super::common::env_brdf(self.base, r, mu), refl)
            }
        };
        let transmission = match v.interface {
            Interface::Opaque => Vec3::ZERO,
            _ => below * (1.0 - m) * self.transmission * v.e_t * v.ms_t * self.base,
        };
        Albedos {
            diffuse: dielectric
                * ((1.0 - self.diffuse_transmission) * self.base
                    + self.diffuse_transmission * self.diffuse_transmission_color)
                + sheen,
            glossy: coat
                + below * (m * metal * v.ms_metal + (1.0 - m) * self.specular * refl * v.ms_r),
            transmission,
        }
    }

    /// True when the specular layer is rough enough to count as a surface for denoising
    /// features (Cycles: α > 0.075).
    pub fn glossy_is_rough(&self) -> bool {
        self.view
            .ggx
            .is_some_and(|g| g.alpha_mean() > super::common::ROUGH_ALPHA)
    }
}

/// glTF's dielectric F0 for an IOR (0 means "infinitely reflective"; bad values use 1.5).
fn ior_f0(ior: f32) -> f32 {
    if ior == 0.0 {
        1.0
    } else if ior.is_finite() && ior >= 1.0 {
        f0_from_eta(ior)
    } else {
        0.04
    }
}
