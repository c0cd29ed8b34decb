//! Writing and reading images: EXR (float, with metadata and passes), PNG (display-referred).
//!
//! ```
//! // The image writers are being written; see the issue tracker.
//! assert_eq!(2 + 2, 4);
//! ```
