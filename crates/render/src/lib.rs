//! Camera, sampler, integrator and film: turns a scene and its acceleration structure into an image.
//!
//! ```
//! // The render core is being written; see the issue tracker.
//! assert_eq!(2 + 2, 4);
//! ```
