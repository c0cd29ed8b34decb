//! The media a path is inside: nested and touching dielectrics (Schmidt & Budge 2002, "Simple
//! Nested Dielectrics in Ray Traced Images", with equal priorities).
//!
//! A path starts in air (IOR 1, no absorption). Crossing into a refractive body pushes its
//! medium; leaving it pops. The current medium is the one entered last. At a refractive
//! surface of material M:
//! - entering M while already inside M is a *false* interface (an overlap of two bodies of the
//!   same material): the ray passes unchanged;
//! - leaving M while M is the current medium is a real interface into the medium below it;
//! - leaving M while inside M but in a medium entered later is a false interface: M's surface
//!   lies inside the later body (a liquid modelled slightly overlapping its glass, as Cycles'
//!   users are told to model it); M is removed from the stack and the ray passes;
//! - leaving M without having entered it (the camera inside, or an open mesh) is a real
//!   interface from M into the current medium.
//!
//! So where a liquid overlaps its glass, exactly one interface (glass → liquid, relative IOR
//! 1.33/1.5) bends and reflects light, and the overlap is counted once: neither air gaps nor
//! double Fresnel. Faces of two bodies that coincide exactly are a single interface when the
//! inner body's face is met first; the other order tracks media as two separate interfaces.

use glam::Vec3;

/// Media one path can be nested in; deeper entries are dropped (the path then treats the
/// innermost it keeps as current).
const DEPTH: usize = 4;

/// One medium: the material whose volume it is, its IOR and absorption per unit length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Medium {
    /// Index of the material whose volume this is.
    pub material: u32,
    /// Index of refraction.
    pub ior: f32,
    /// Absorption coefficient per unit length.
    pub sigma_a: Vec3,
}

/// What a refractive surface is for a path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Crossing {
    /// Not an interface: the ray passes straight on.
    False,
    /// A real interface from IOR `from` (the viewer's side) into IOR `to`.
    Real {
        /// IOR on the ray's side.
        from: f32,
        /// IOR on the far side.
        to: f32,
    },
}

/// The stack of media a path is inside.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MediumStack {
    len: u8,
    media: [Option<Medium>; DEPTH],
}

impl MediumStack {
    #[cfg(test)]
    fn entries(&self) -> impl Iterator<Item = &Medium> {
        self.media[..self.len as usize].iter().flatten()
    }

    /// The current medium, `None` in air.
    pub fn top(&self) -> Option<&Medium> {
        self.len
            .checked_sub(1)
            .and_then(|i| self.media[i as usize].as_ref())
    }

    /// Absorption coefficient of the current medium.
    pub fn sigma_a(&self) -> Vec3 {
        self.top().map_or(Vec3::ZERO, |m| m.sigma_a)
    }

    fn ior_top(&self) -> f32 {
        self.top().map_or(1.0, |m| m.ior)
    }

    fn position(&self, material: u32) -> Option<usize> {
        self.media[..self.len as usize]
            .iter()
            .position(|m| m.is_some_and(|m| m.material == material))
    }

    /// What a surface of `medium`'s material is when the ray `entering` (crosses it against
    /// its front-face normal) or leaves.
    pub fn classify(&self, medium: &Medium, entering: bool) -> Crossing {
        match (entering, self.position(medium.material)) {
            (true, Some(_)) => Crossing::False,
            (true, None) => Crossing::Real {
                from: self.ior_top(),
                to: medium.ior,
            },
            (false, Some(i)) if i + 1 == self.len as usize => {
                let below = i
                    .checked_sub(1)
                    .and_then(|j| self.media[j])
                    .map_or(1.0, |m| m.ior);
                Crossing::Real {
                    from: medium.ior,
                    to: below,
                }
            }
            (false, Some(_)) => Crossing::False,
            (false, None) => Crossing::Real {
                from: medium.ior,
                to: self.ior_top(),
            },
        }
    }

    /// Updates the stack for a ray that passed a surface of `medium` (a false interface, or a
    /// real one it was transmitted through).
    pub fn cross(&mut self, medium: &Medium, entering: bool) {
        match (entering, self.position(medium.material)) {
            (true, Some(_)) => {}
            (true, None) => {
                if (self.len as usize) < DEPTH {
                    self.media[self.len as usize] = Some(*medium);
                    self.len += 1;
                }
            }
            (false, Some(i)) => {
                let n = self.len as usize;
                self.media.copy_within(i + 1..n, i);
                self.media[n - 1] = None;
                self.len -= 1;
            }
            (false, None) => {}
        }
    }

    /// True outside every medium.
    #[cfg(test)]
    pub fn is_empty(&self) -> bool {
        self.entries().next().is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn m(material: u32, ior: f32) -> Medium {
        Medium {
            material,
            ior,
            sigma_a: Vec3::splat(material as f32),
        }
    }

    /// A liquid (1.33) overlapping the inside of its glass (1.5), crossed along a line: air →
    /// glass → (overlap) liquid → glass → air, one interface at each boundary.
    #[test]
    fn overlapping_liquid_in_glass() {
        let (glass, liquid) = (m(1, 1.5), m(2, 1.33));
        let mut s = MediumStack::default();
        let mut real = Vec::new();
        let mut pass = |s: &mut MediumStack, med: &Medium, entering: bool| {
            let c = s.classify(med, entering);
            if let Crossing::Real { from, to } = c {
                real.push((from, to));
            }
            s.cross(med, entering);
        };
        pass(&mut s, &glass, true); // outer wall
        assert_eq!(s.sigma_a(), glass.sigma_a);
        pass(&mut s, &liquid, true); // liquid surface inside the glass wall
        pass(&mut s, &glass, false); // inner wall, inside the liquid: false
        assert_eq!(s.top(), Some(&liquid));
        pass(&mut s, &glass, true); // far inner wall
        pass(&mut s, &liquid, false); // liquid surface inside the far wall: false
        pass(&mut s, &glass, false); // far outer wall
        assert!(s.is_empty());
        assert_eq!(
            real,
            [(1.0, 1.5), (1.5, 1.33), (1.33, 1.5), (1.5, 1.0)],
            "one interface per boundary"
        );
    }

    #[test]
    fn same_material_overlap_and_stray_exit() {
        let glass = m(1, 1.5);
        let mut s = MediumStack::default();
        s.cross(&glass, true);
        // A second shell of the same glass: false.
        assert_eq!(s.classify(&glass, true), Crossing::False);
        // Leaving a body never entered (camera inside it): real, into the current medium.
        let water = m(3, 1.33);
        assert_eq!(
            s.classify(&water, false),
            Crossing::Real {
                from: 1.33,
                to: 1.5
            }
        );
        s.cross(&water, false);
        assert_eq!(s.top(), Some(&glass));
        // The stack is bounded.
        for k in 10..20 {
            s.cross(&m(k, 1.1), true);
        }
        assert_eq!(s.entries().count(), DEPTH);
    }
}
