//! glTF animations (SPEC §7): channels read from the JSON (the `gltf` crate refuses
//! `KHR_animation_pointer` channels, which have no `target.node`), samplers evaluated at a time.
//!
//! Interpolation follows the glTF 2.0 specification, Appendix C: STEP holds the key before the
//! time, LINEAR interpolates (quaternions by spherical linear interpolation along the shorter
//! arc), CUBICSPLINE is the cubic Hermite spline of the keys and their tangents. Before the first
//! key and after the last, a sampler holds its first or last value (clamped). Evaluation runs in
//! f64 on the file's f32 keys.

use glam::{DQuat, DVec3};
use serde_json::Value;

use crate::accessor::{read_f32, Buffers};
use crate::error::Error;
use crate::pointer::{self, Pointer};

pub(crate) use crate::pointer::NodeProperty;

/// Which animations a time evaluates (`--animation NAME|INDEX`).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum AnimationSelection {
    /// Every animation together, as Blender's timeline plays every object's action.
    #[default]
    All,
    /// The animation at this index of the file's `animations`.
    Index(usize),
    /// The (first) animation with this name.
    Name(String),
}

/// An animation of the file, for listings (`aperture info`).
#[derive(Debug, Clone, PartialEq)]
pub struct AnimationInfo {
    /// Index in the file's `animations`.
    pub index: usize,
    /// The animation's name, if any.
    pub name: Option<String>,
    /// Earliest key time of its samplers, seconds.
    pub start: f32,
    /// Latest key time of its samplers, seconds (the duration, for an animation starting at 0).
    pub end: f32,
    /// Channels it has (including those aperture ignores).
    pub channels: usize,
    /// Whether the current load evaluates it (see [`AnimationSelection`]).
    pub selected: bool,
}

/// How a sampler interpolates between keys.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Interpolation {
    Step,
    Linear,
    CubicSpline,
}

/// What a channel animates.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Target {
    /// A node's translation, rotation, scale or morph weights (`target.node` + `target.path`, or a
    /// `/nodes/{i}/...` pointer).
    Node(usize, NodeProperty),
    /// Anything else `KHR_animation_pointer` can point at that aperture evaluates.
    Pointer(Pointer),
}

/// Keys of one sampler: `times` ascending; `values` holds `width` floats per key (three times
/// that for CUBICSPLINE: in-tangent, value, out-tangent).
#[derive(Debug, Clone)]
pub(crate) struct Sampler {
    times: Vec<f32>,
    values: Vec<f32>,
    width: usize,
    interpolation: Interpolation,
}

/// One evaluated channel.
#[derive(Debug, Clone)]
pub(crate) struct Channel {
    pub target: Target,
    pub sampler: Sampler,
}

/// Every animation of a file, parsed.
#[derive(Debug, Clone, Default)]
pub(crate) struct Animations {
    /// Channels of the selected animations that aperture evaluates.
    pub channels: Vec<Channel>,
    /// Every animation, for listings.
    pub info: Vec<AnimationInfo>,
    /// Pointers that were ignored (what they point at is not animated by aperture).
    pub ignored_pointers: Vec<String>,
    /// What the user should know of channels that are evaluated otherwise than keyed.
    pub warnings: Vec<String>,
}

impl Sampler {
    /// The sampler's value at `time`, `width` floats (quaternions normalised by the caller).
    pub fn sample(&self, time: f32, rotation: bool) -> Vec<f64> {
        let w = self.width;
        let n = self.times.len();
        let stride = if self.interpolation == Interpolation::CubicSpline {
            3 * w
        } else {
            w
        };
        let value_at = |k: usize| -> Vec<f64> {
            let start = k * stride
                + if self.interpolation == Interpolation::CubicSpline {
                    w
                } else {
                    0
                };
            self.values[start..start + w]
                .iter()
                .map(|&v| f64::from(v))
                .collect()
        };
        // Clamped outside the keys' range (and a single key is a constant).
        if n == 1 || time <= self.times[0] {
            return value_at(0);
        }
        if time >= self.times[n - 1] {
            return value_at(n - 1);
        }
        // The last key at or before `time`: times[k] <= time < times[k + 1].
        let k = self.times.partition_point(|&t| t <= time).saturating_sub(1);
        let (t0, t1) = (f64::from(self.times[k]), f64::from(self.times[k + 1]));
        let dt = t1 - t0;
        if dt <= 0.0 {
            return value_at(k + 1);
        }
        let s = (f64::from(time) - t0) / dt;
        match self.interpolation {
            Interpolation::Step => value_at(k),
            Interpolation::Linear if rotation && w == 4 => {
                let q = |v: Vec<f64>| DQuat::from_xyzw(v[0], v[1], v[2], v[3]);
                let r = slerp(q(value_at(k)), q(value_at(k + 1)), s);
                r.to_array().to_vec()
            }
            Interpolation::Linear => value_at(k)
                .iter()
                .zip(value_at(k + 1))
                .map(|(a, b)| a + s * (b - a))
                .collect(),
            Interpolation::CubicSpline => {
                let part = |key: usize, which: usize| -> Vec<f64> {
                    let start = key * stride + which * w;
                    self.values[start..start + w]
                        .iter()
                        .map(|&v| f64::from(v))
                        .collect()
                };
                let (v0, b0) = (part(k, 1), part(k, 2));
                let (a1, v1) = (part(k + 1, 0), part(k + 1, 1));
                let (s2, s3) = (s * s, s * s * s);
                let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
                let h10 = s3 - 2.0 * s2 + s;
                let h01 = -2.0 * s3 + 3.0 * s2;
                let h11 = s3 - s2;
                (0..w)
                    .map(|i| h00 * v0[i] + h10 * dt * b0[i] + h01 * v1[i] + h11 * dt * a1[i])
                    .collect()
            }
        }
    }
}

/// Spherical linear interpolation along the shorter arc (glTF 2.0 Appendix C).
pub(crate) fn slerp(a: DQuat, b: DQuat, s: f64) -> DQuat {
    let mut dot = a.dot(b);
    let b = if dot < 0.0 {
        dot = -dot;
        -b
    } else {
        b
    };
    if dot > 1.0 - 1e-9 {
        // Nearly the same rotation: the arc is a line.
        return (a * (1.0 - s) + b * s).normalize();
    }
    let theta = dot.acos();
    let sin = theta.sin();
    let wa = ((1.0 - s) * theta).sin() / sin;
    let wb = (s * theta).sin() / sin;
    a * wa + b * wb
}

/// A translation, rotation or scale value from a sample.
pub(crate) fn vec3(v: &[f64]) -> DVec3 {
    DVec3::new(v[0], v[1], v[2])
}

/// A rotation from a sample, normalised (CUBICSPLINE rotations leave the unit sphere).
pub(crate) fn quat(v: &[f64]) -> Option<DQuat> {
    let q = DQuat::from_xyzw(v[0], v[1], v[2], v[3]);
    (q.length_squared() > 0.0 && q.is_finite()).then(|| q.normalize())
}

fn invalid(at: String, reason: impl Into<String>) -> Error {
    Error::Invalid {
        at,
        reason: reason.into(),
    }
}

fn index_of(v: &Value, at: &str) -> Result<usize, Error> {
    v.as_u64()
        .and_then(|i| usize::try_from(i).ok())
        .ok_or_else(|| invalid(at.into(), format!("{v} is not an index")))
}

/// Floats of an accessor named by index, `dims` per element.
fn accessor_floats(
    doc: &gltf::Document,
    buffers: &Buffers,
    index: usize,
    at: &str,
) -> Result<(Vec<f32>, usize), Error> {
    let acc = doc
        .accessors()
        .nth(index)
        .ok_or_else(|| invalid(at.into(), format!("accessor {index} does not exist")))?;
    read_f32(&acc, buffers, at)
}

/// Reads one sampler; `width` of its elements is decided later by the channel's target.
fn read_sampler(
    doc: &gltf::Document,
    buffers: &Buffers,
    json: &Value,
    at: &str,
) -> Result<(Vec<f32>, Vec<f32>, usize, Interpolation), Error> {
    let interpolation = match json.get("interpolation").and_then(Value::as_str) {
        None | Some("LINEAR") => Interpolation::Linear,
        Some("STEP") => Interpolation::Step,
        Some("CUBICSPLINE") => Interpolation::CubicSpline,
        Some(other) => {
            return Err(invalid(
                format!("{at}.interpolation"),
                format!("{other:?} is not STEP, LINEAR or CUBICSPLINE"),
            ))
        }
    };
    let input = index_of(
        json.get("input").unwrap_or(&Value::Null),
        &format!("{at}.input"),
    )?;
    let output = index_of(
        json.get("output").unwrap_or(&Value::Null),
        &format!("{at}.output"),
    )?;
    let (times, dims) = accessor_floats(doc, buffers, input, &format!("{at}.input"))?;
    if dims != 1 {
        return Err(invalid(format!("{at}.input"), "key times must be SCALAR"));
    }
    if times.is_empty() {
        return Err(invalid(format!("{at}.input"), "no key times"));
    }
    if let Some(t) = times.iter().find(|t| !t.is_finite()) {
        return Err(Error::NonFinite {
            at: format!("{at}.input"),
            value: t.to_string(),
        });
    }
    if times.windows(2).any(|w| w[1] < w[0]) {
        return Err(invalid(
            format!("{at}.input"),
            "key times are not in increasing order",
        ));
    }
    let (values, dims) = accessor_floats(doc, buffers, output, &format!("{at}.output"))?;
    if let Some(v) = values.iter().find(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            at: format!("{at}.output"),
            value: v.to_string(),
        });
    }
    Ok((times, values, dims, interpolation))
}

/// The target of a channel: `None` when aperture does not animate it (pointers are listed in
/// `ignored`).
fn read_target(
    json: &Value,
    at: &str,
    root: &Value,
    ignored: &mut Vec<String>,
) -> Result<Option<Target>, Error> {
    let target = json
        .get("target")
        .ok_or_else(|| invalid(format!("{at}.target"), "missing"))?;
    let path = target.get("path").and_then(Value::as_str).unwrap_or("");
    let node_property = |p: &str| match p {
        "translation" => Some(NodeProperty::Translation),
        "rotation" => Some(NodeProperty::Rotation),
        "scale" => Some(NodeProperty::Scale),
        "weights" => Some(NodeProperty::Weights),
        _ => None,
    };
    if path == "pointer" {
        let Some(p) = target
            .get("extensions")
            .and_then(|e| e.get("KHR_animation_pointer"))
            .and_then(|e| e.get("pointer"))
            .and_then(Value::as_str)
        else {
            return Err(invalid(
                format!("{at}.target.extensions.KHR_animation_pointer.pointer"),
                "missing (the path is \"pointer\")",
            ));
        };
        return Ok(match pointer::parse(p, root) {
            Some(Pointer::Node(node, prop)) => Some(Target::Node(node, prop)),
            Some(other) => Some(Target::Pointer(other)),
            None => {
                if !ignored.iter().any(|i| i == p) {
                    ignored.push(p.to_owned());
                }
                None
            }
        });
    }
    let Some(prop) = node_property(path) else {
        return Err(invalid(
            format!("{at}.target.path"),
            format!("{path:?} is not translation, rotation, scale, weights or pointer"),
        ));
    };
    let node = index_of(
        target.get("node").unwrap_or(&Value::Null),
        &format!("{at}.target.node"),
    )?;
    if node
        >= root
            .get("nodes")
            .and_then(Value::as_array)
            .map_or(0, Vec::len)
    {
        return Err(invalid(
            format!("{at}.target.node"),
            format!("node {node} does not exist"),
        ));
    }
    Ok(Some(Target::Node(node, prop)))
}

/// Floats per key element a target needs (`None`: any, as for morph weights).
fn target_width(target: &Target) -> Option<usize> {
    match target {
        Target::Node(_, NodeProperty::Translation | NodeProperty::Scale) => Some(3),
        Target::Node(_, NodeProperty::Rotation) => Some(4),
        Target::Node(_, NodeProperty::Weights) => None,
        Target::Pointer(p) => p.width(),
    }
}

/// Parses every animation of `root` (the raw JSON), keeping the channels of the selected ones.
pub(crate) fn parse(
    doc: &gltf::Document,
    buffers: &Buffers,
    root: &Value,
    selection: &AnimationSelection,
) -> Result<Animations, Error> {
    let list = root
        .get("animations")
        .and_then(Value::as_array)
        .cloned()
        .unwrap_or_default();
    let chosen = |i: usize, name: Option<&str>| match selection {
        AnimationSelection::All => true,
        AnimationSelection::Index(k) => *k == i,
        AnimationSelection::Name(n) => name == Some(n.as_str()),
    };
    let mut out = Animations::default();
    let mut name_taken = false;
    for (a, anim) in list.iter().enumerate() {
        let name = anim.get("name").and_then(Value::as_str);
        let mut selected = chosen(a, name);
        if let AnimationSelection::Name(_) = selection {
            // The first of several animations with the name.
            selected &= !name_taken;
            name_taken |= selected;
        }
        let info = read_animation(doc, buffers, root, anim, a, selected, &mut out)?;
        out.info.push(info);
    }
    match selection {
        AnimationSelection::Index(i) if *i >= list.len() => {
            return Err(Error::NoSuchAnimation {
                wanted: i.to_string(),
                available: names(&out.info),
            })
        }
        AnimationSelection::Name(n) if !name_taken => {
            return Err(Error::NoSuchAnimation {
                wanted: format!("{n:?}"),
                available: names(&out.info),
            })
        }
        _ => {}
    }
    Ok(out)
}

/// A sampler as read: key times, values, components per element and interpolation.
type SamplerKeys = (Vec<f32>, Vec<f32>, usize, Interpolation);

/// Reads animation `a` (`anim`), adding its channels to `out` when `selected`; its listing.
fn read_animation(
    doc: &gltf::Document,
    buffers: &Buffers,
    root: &Value,
    anim: &Value,
    a: usize,
    selected: bool,
    out: &mut Animations,
) -> Result<AnimationInfo, Error> {
    let at = format!("animations[{a}]");
    let name = anim.get("name").and_then(Value::as_str);
    let samplers = anim
        .get("samplers")
        .and_then(Value::as_array)
        .cloned()
        .unwrap_or_default();
    let channels = anim
        .get("channels")
        .and_then(Value::as_array)
        .cloned()
        .unwrap_or_default();
    let mut read = Vec::with_capacity(samplers.len());
    for (s, sampler) in samplers.iter().enumerate() {
        read.push(Some(read_sampler(
            doc,
            buffers,
            sampler,
            &format!("{at}.samplers[{s}]"),
        )?));
    }
    let (mut start, mut end) = (f32::INFINITY, f32::NEG_INFINITY);
    for (c, channel) in channels.iter().enumerate() {
        let (first, last) = read_channel(channel, &at, c, &read, root, selected, out)?;
        start = start.min(first);
        end = end.max(last);
    }
    if !start.is_finite() {
        (start, end) = (0.0, 0.0);
    }
    Ok(AnimationInfo {
        index: a,
        name: name.map(str::to_owned),
        start,
        end,
        channels: channels.len(),
        selected,
    })
}

/// Reads channel `c` of the animation at `at`, checking its sampler's keys against its target,
/// and adds it to `out` when `selected` and aperture animates its target. Returns the first and
/// last key times of its sampler.
fn read_channel(
    channel: &Value,
    at: &str,
    c: usize,
    read: &[Option<SamplerKeys>],
    root: &Value,
    selected: bool,
    out: &mut Animations,
) -> Result<(f32, f32), Error> {
    let cat = format!("{at}.channels[{c}]");
    let s = index_of(
        channel.get("sampler").unwrap_or(&Value::Null),
        &format!("{cat}.sampler"),
    )?;
    let Some(Some((times, values, dims, interpolation))) = read.get(s) else {
        return Err(invalid(
            format!("{cat}.sampler"),
            format!("sampler {s} does not exist"),
        ));
    };
    let span = (times[0], times[times.len() - 1]);
    let Some(target) = read_target(channel, &cat, root, &mut out.ignored_pointers)? else {
        return Ok(span);
    };
    let keys = times.len()
        * if *interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
    let floats = values.len();
    let width = match target_width(&target) {
        Some(w) => w,
        None if floats % keys == 0 => floats / keys,
        None => 0,
    };
    if width == 0 || floats != keys * width {
        return Err(invalid(
            format!("{at}.samplers[{s}].output"),
            format!(
                "{floats} values ({dims} per element) for {} keys of {} floats each ({interpolation:?})",
                times.len(),
                width.max(1)
            ),
        ));
    }
    if selected {
        let (values, interpolation) = match target {
            Target::Pointer(Pointer::NodeVisible(_)) => {
                bool_keys(values, *interpolation, &cat, out)
            }
            _ => (values.clone(), *interpolation),
        };
        out.channels.push(Channel {
            target,
            sampler: Sampler {
                times: times.clone(),
                values,
                width,
                interpolation,
            },
        });
    }
    Ok(span)
}

/// The keys of a bool channel (`KHR_node_visibility`'s `visible`) as STEP keys: a bool cannot
/// be interpolated, and `KHR_animation_pointer` requires STEP for it; a LINEAR or CUBICSPLINE
/// sampler is held at each key's value (warned), not blended into a value that is neither.
fn bool_keys(
    values: &[f32],
    interpolation: Interpolation,
    at: &str,
    out: &mut Animations,
) -> (Vec<f32>, Interpolation) {
    if interpolation == Interpolation::Step {
        return (values.to_vec(), interpolation);
    }
    out.warnings.push(format!(
        "{at}: KHR_node_visibility's visible is a bool keyed with {interpolation:?} \
         interpolation (KHR_animation_pointer requires STEP): each key held until the next"
    ));
    let keys = match interpolation {
        // In-tangent, value, out-tangent per key: the values only.
        Interpolation::CubicSpline => values.iter().skip(1).step_by(3).copied().collect(),
        _ => values.to_vec(),
    };
    (keys, Interpolation::Step)
}

/// The animations as `0 "Walk", 1 (unnamed)` for messages.
fn names(info: &[AnimationInfo]) -> String {
    if info.is_empty() {
        return "the file has no animation".into();
    }
    info.iter()
        .map(|a| match &a.name {
            Some(n) => format!("{} {n:?}", a.index),
            None => format!("{} (unnamed)", a.index),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests;
