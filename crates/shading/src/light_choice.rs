//! Which light a path vertex samples: one shadow ray per vertex, however many lights the scene
//! has (as pbrt-v4's exhaustive light sampler; an environment image keeps its own shadow ray).
//!
//! Every punctual light and the scene's emissive triangles (as one candidate) get an importance
//! at the vertex, and one is picked in proportion to it:
//! - a punctual light, its unoccluded irradiance on the side the vertex receives light from,
//!   exactly (zero only where it lights nothing);
//! - the emitters, a bound from their box, normal cone and power ([`LightBounds`], pbrt-v4's
//!   `LightBounds::Importance`): zero only where no emitter can light the vertex.
//!
//! A light of zero importance contributes nothing there, so the pick is unbiased; a light of
//! positive importance is picked with that probability and its contribution divided by it.
//! Scenes with a single candidate never pick (see [`Candidates::choose`]).

use crate::color::luminance;
use crate::light_bounds::LightBounds;
use crate::punctual::punctual_incident;
use aperture_scene::Light;
use glam::Vec3;

/// The importance of a punctual light at a point `p` with normal `n` facing the side light is
/// received from (both sides when `two_sided`): its unoccluded irradiance there, exactly.
#[inline]
pub fn punctual_importance(light: &Light, p: Vec3, n: Vec3, two_sided: bool) -> f32 {
    let Some((wi, _, e)) = punctual_incident(light, p) else {
        return 0.0;
    };
    let cos = n.dot(wi);
    let cos = if two_sided { cos.abs() } else { cos };
    let importance = luminance(e) * cos;
    if importance.is_finite() && importance > 0.0 {
        importance
    } else {
        0.0
    }
}

/// The light a vertex samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Pick {
    /// The punctual light of this index.
    Punctual(usize),
    /// One of the emissive triangles (the caller picks which, by power, with [`Choice::u`]).
    Emitters,
    /// The emissive triangle of this index in [`crate::lights::EmissiveLights::triangles`],
    /// picked by the light tree ([`crate::light_tree`]).
    Triangle(usize),
}

/// A vertex's pick: which light, with what probability, and the probability that the
/// emitters are picked there (for the MIS weight of emitters that BSDF sampling meets).
#[derive(Debug, Clone, Copy)]
pub struct Choice {
    /// The light picked, `None` when there is nothing to pick.
    pub pick: Option<Pick>,
    /// Probability of that pick.
    pub probability: f32,
    /// Probability of picking the emitters here.
    pub emitters: f32,
    /// The uniform number left over after the pick, in `[0, 1)`.
    pub u: f32,
}

/// What a vertex may pick from: the punctual lights and the emitters' bound.
pub struct Candidates<'a> {
    /// The scene's punctual lights.
    pub lights: &'a [Light],
    /// The bound of the emissive triangles, if any ([`LightBounds::emitters`]).
    pub emitters: Option<&'a LightBounds>,
}

impl Candidates<'_> {
    /// Whether there is a choice to make (two candidates or more).
    pub fn choose(&self) -> bool {
        self.lights.len() + usize::from(self.emitters.is_some()) >= 2
    }

    /// One light at `p` (normal `n` on the side light is received from; both sides when
    /// `two_sided`) in proportion to the importances, from the uniform `u` (remapped into
    /// [`Choice::u`]). `pick` is `None` when no light can light the point.
    pub fn pick(&self, p: Vec3, n: Vec3, two_sided: bool, u: f32) -> Choice {
        // Up to `KEPT` punctual importances are kept from the sum for the walk; more are
        // computed again (the same arithmetic, so the same values).
        const KEPT: usize = 8;
        let mut kept = [0.0f32; KEPT];
        let w_emit = self.emitters.map_or(0.0, |b| b.importance(p, n, two_sided));
        let mut total = 0.0f32;
        for (i, l) in self.lights.iter().enumerate() {
            let w = punctual_importance(l, p, n, two_sided);
            if let Some(k) = kept.get_mut(i) {
                *k = w;
            }
            total += w;
        }
        total += w_emit;
        let mut choice = Choice {
            pick: None,
            probability: 0.0,
            emitters: 0.0,
            u,
        };
        if !(total > 0.0 && total.is_finite()) {
            return choice;
        }
        choice.emitters = w_emit / total;
        let weight = |pick: Pick| match pick {
            Pick::Punctual(i) => kept
                .get(i)
                .copied()
                .unwrap_or_else(|| punctual_importance(&self.lights[i], p, n, two_sided)),
            Pick::Emitters | Pick::Triangle(_) => w_emit,
        };
        // The same weights in the same order as `total`, so the walk ends where `target`
        // falls; should rounding leave it past the end, the last candidate that can light the
        // point takes the rest.
        let all = (0..self.lights.len())
            .map(Pick::Punctual)
            .chain([Pick::Emitters])
            .map(|pick| (pick, weight(pick)));
        if let Some((pick, w, x)) = walk(all, u * total) {
            choice.pick = Some(pick);
            choice.probability = w / total;
            choice.u = remap(x, w);
        }
        choice
    }
}

/// `x / w` in `[0, 1)`.
#[inline]
pub(crate) fn remap(x: f32, w: f32) -> f32 {
    (x / w).clamp(0.0, 1.0 - f32::EPSILON / 2.0)
}

/// The candidate where `target` (a uniform number times the weights' total) falls when the
/// `weighted` candidates are laid end to end in their order: the candidate, its weight and how
/// far into it `target` falls. Candidates of no weight are skipped; should rounding leave
/// `target` past the end, the last candidate with weight takes it. The caller's total must sum
/// the same weights in the same order.
#[inline]
pub(crate) fn walk<T>(
    weighted: impl IntoIterator<Item = (T, f32)>,
    target: f32,
) -> Option<(T, f32, f32)> {
    let mut below = 0.0f32;
    let mut last = None;
    for (c, w) in weighted {
        if w <= 0.0 {
            continue;
        }
        let end = target < below + w;
        last = Some((c, w, below));
        if end {
            break;
        }
        below += w;
    }
    last.map(|(c, w, below)| (c, w, target - below))
}

#[cfg(test)]
mod tests;
