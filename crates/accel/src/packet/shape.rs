//! What a packet is: how many rays, and how close in direction they must be.

/// Rays per packet: one AVX2 lane each.
pub const PACKET_LANES: usize = 8;

/// A run is traced as a packet when every ray's direction is within this cosine of the first
/// ray's (about 8°): wider runs share too little of their walks to gain.
pub const PACKET_CONE_COS: f32 = 0.99;
