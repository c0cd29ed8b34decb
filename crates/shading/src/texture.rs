//! Texture lookups: `KHR_texture_transform`, wrap modes, bilinear or nearest filtering, and sRGB
//! decoding (a 256-entry table for 8-bit texels, so decoding costs a load).

use aperture_scene::{ColorSpace, Filter, Texels, Texture, TextureTransform, Wrap};
use glam::{Vec2, Vec4};
use std::sync::OnceLock;

use crate::color::srgb_to_linear;

fn srgb_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0)))
}

/// Applies `KHR_texture_transform`: `offset + rotate(rotation) · (scale · uv)`, the rotation
/// counter-clockwise in UV space (v points down), as the extension's example defines it.
pub fn transform_uv(t: &TextureTransform, uv: Vec2) -> Vec2 {
    let s = uv * t.scale;
    let (sin, cos) = t.rotation.sin_cos();
    t.offset + Vec2::new(cos * s.x + sin * s.y, -sin * s.x + cos * s.y)
}

/// Wraps an integer texel coordinate into `[0, n)`.
#[inline]
fn wrap(i: i64, n: u32, mode: Wrap) -> u32 {
    let n = n as i64;
    // Most coordinates are inside already, where every mode is the identity: skip the
    // 64-bit divisions of the remainders.
    if (0..n).contains(&i) {
        return i as u32;
    }
    let w = match mode {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            let p = i.rem_euclid(2 * n);
            if p < n {
                p
            } else {
                2 * n - 1 - p
            }
        }
    };
    w as u32
}

/// One texel, decoded to linear RGBA (alpha is always linear).
#[inline(always)]
fn texel(tex: &Texture, x: u32, y: u32) -> Vec4 {
    let i = y as usize * tex.width as usize + x as usize;
    match (&tex.texels, tex.color_space) {
        (Texels::Rgba8(t), ColorSpace::Srgb) => {
            let lut = srgb_table();
            let [r, g, b, a] = t[i];
            Vec4::new(
                lut[r as usize],
                lut[g as usize],
                lut[b as usize],
                a as f32 / 255.0,
            )
        }
        (Texels::Rgba8(t), ColorSpace::Linear) => Vec4::from_array(t[i].map(|c| c as f32 / 255.0)),
        (Texels::Rgba32F(t), ColorSpace::Srgb) => {
            let [r, g, b, a] = t[i];
            Vec4::new(srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b), a)
        }
        (Texels::Rgba32F(t), ColorSpace::Linear) => Vec4::from_array(t[i]),
    }
}

/// Looks up `tex` at `uv` (glTF convention: (0, 0) is the image's top-left corner).
pub fn sample(tex: &Texture, uv: Vec2) -> Vec4 {
    if !uv.is_finite() || tex.width == 0 || tex.height == 0 {
        return Vec4::ONE;
    }
    let (w, h) = (tex.width, tex.height);
    let s = &tex.sampler;
    // Texel centres sit at half-integers.
    let x = uv.x * w as f32 - 0.5;
    let y = uv.y * h as f32 - 0.5;
    match s.mag_filter {
        Filter::Nearest => {
            let xi = wrap((x + 0.5).floor() as i64, w, s.wrap_u);
            let yi = wrap((y + 0.5).floor() as i64, h, s.wrap_v);
            texel(tex, xi, yi)
        }
        Filter::Linear => {
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = (x - x0, y - y0);
            let (x0, y0) = (x0 as i64, y0 as i64);
            let xa = wrap(x0, w, s.wrap_u);
            let xb = wrap(x0 + 1, w, s.wrap_u);
            let ya = wrap(y0, h, s.wrap_v);
            let yb = wrap(y0 + 1, h, s.wrap_v);
            let top = texel(tex, xa, ya).lerp(texel(tex, xb, ya), fx);
            let bottom = texel(tex, xa, yb).lerp(texel(tex, xb, yb), fx);
            top.lerp(bottom, fy)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aperture_scene::Sampler;

    fn tex2x1(color_space: ColorSpace, sampler: Sampler) -> Texture {
        Texture {
            name: None,
            width: 2,
            height: 1,
            texels: Texels::Rgba8(vec![[0, 0, 0, 255], [255, 128, 255, 0]]),
            color_space,
            sampler,
        }
    }

    #[test]
    fn srgb_decoding_and_bilinear() {
        let t = tex2x1(ColorSpace::Srgb, Sampler::default());
        // Texel centres.
        let a = sample(&t, Vec2::new(0.25, 0.5));
        let b = sample(&t, Vec2::new(0.75, 0.5));
        assert_eq!(a, Vec4::new(0.0, 0.0, 0.0, 1.0));
        assert!((b.y - srgb_to_linear(128.0 / 255.0)).abs() < 1e-6);
        assert!((b.y - 0.2158605).abs() < 1e-4);
        // Halfway between: the mean of the linear values (repeat wrap on both sides).
        let m = sample(&t, Vec2::new(0.5, 0.5));
        assert!((m.x - 0.5).abs() < 1e-6 && (m.w - 0.5).abs() < 1e-6);
        // Linear data is not decoded.
        let l = sample(
            &tex2x1(ColorSpace::Linear, Sampler::default()),
            Vec2::new(0.75, 0.5),
        );
        assert!((l.y - 128.0 / 255.0).abs() < 1e-6);
    }

    #[test]
    fn wrap_modes() {
        assert_eq!(wrap(-1, 4, Wrap::Repeat), 3);
        assert_eq!(wrap(-1, 4, Wrap::ClampToEdge), 0);
        assert_eq!(wrap(-1, 4, Wrap::MirroredRepeat), 0);
        assert_eq!(wrap(5, 4, Wrap::MirroredRepeat), 2);
        assert_eq!(wrap(9, 4, Wrap::Repeat), 1);
        let clamp = Sampler {
            wrap_u: Wrap::ClampToEdge,
            wrap_v: Wrap::ClampToEdge,
            mag_filter: Filter::Nearest,
        };
        let t = tex2x1(ColorSpace::Linear, clamp);
        assert_eq!(sample(&t, Vec2::new(7.0, 0.5)).x, 1.0);
        assert_eq!(sample(&t, Vec2::new(-7.0, 0.5)).x, 0.0);
    }

    #[test]
    fn texture_transform_matches_the_extension_example() {
        // The extension's example: offset (0, 1), rotation 90°, scale 0.5 uses the lower-left
        // quadrant, i.e. u ∈ [0, 0.5], v ∈ [0.5, 1].
        let t = TextureTransform {
            offset: Vec2::new(0.0, 1.0),
            rotation: std::f32::consts::FRAC_PI_2,
            scale: Vec2::splat(0.5),
        };
        for uv in [
            Vec2::ZERO,
            Vec2::ONE,
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
        ] {
            let o = transform_uv(&t, uv);
            assert!((-1e-6..=0.5 + 1e-6).contains(&o.x), "{o}");
            assert!((0.5 - 1e-6..=1.0 + 1e-6).contains(&o.y), "{o}");
        }
    }
}
