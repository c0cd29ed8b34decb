//! Realistic lenses shared by value: a camera stays `Copy` (it is copied per tile and per
//! motion key), so it holds a `&'static` lens, made once per distinct prescription, focus and
//! film and kept for the process's life. A lens is a few kilobytes (its surfaces and 64
//! pupil bounds), and making one traces a million rays, so sharing also saves the motion
//! keys, the Vector pass's neighbour frames and a session's repeated renders that work.

use super::RealisticLens;
use aperture_scene::{Dof, LensPrescription, SensorFit};
use std::collections::HashMap;
use std::sync::{Mutex, PoisonError};

/// What a lens is made of, bit for bit.
type Key = Vec<u32>;

/// The lenses made so far.
static LENSES: Mutex<Option<HashMap<Key, &'static Result<RealisticLens, String>>>> =
    Mutex::new(None);

/// The key of the lens of `p` under `dof` for a `width × height` image.
fn key(p: &LensPrescription, dof: &Dof, width: u32, height: u32) -> Key {
    let mut k = vec![width, height];
    for s in &p.surfaces {
        k.extend([s.radius, s.thickness, s.ior, s.aperture].map(f32::to_bits));
    }
    k.push(p.fstop.map_or(u32::MAX, f32::to_bits));
    k.extend([dof.focus_distance, dof.sensor_width, dof.sensor_height].map(f32::to_bits));
    k.push(match dof.sensor_fit {
        SensorFit::Auto => 0,
        SensorFit::Horizontal => 1,
        SensorFit::Vertical => 2,
    });
    k
}

/// The lens of prescription `p` under `dof` for a `width × height` image (or why it cannot
/// image), made on first use.
pub fn interned(
    p: &LensPrescription,
    dof: &Dof,
    width: u32,
    height: u32,
) -> &'static Result<RealisticLens, String> {
    let k = key(p, dof, width, height);
    if let Some(lens) = LENSES
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .as_ref()
        .and_then(|m| m.get(&k))
    {
        return lens;
    }
    // Made outside the lock (it takes a while); two threads making the same one keep the
    // first stored.
    let made: &'static _ = Box::leak(Box::new(RealisticLens::new(p, dof, width, height)));
    let mut map = LENSES.lock().unwrap_or_else(PoisonError::into_inner);
    map.get_or_insert_with(HashMap::new)
        .entry(k)
        .or_insert(made)
}
