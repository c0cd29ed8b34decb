use std::path::PathBuf;

/// Everything that can go wrong while loading a scene. Each variant says *where* in the file:
/// `at` fields are glTF JSON paths such as `meshes[2].primitives[0].indices`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file that failed.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Something the renderer does not implement.
    #[error("unsupported: {what}")]
    Unsupported {
        /// What is not supported.
        what: String,
    },
    /// The file lists an extension in `extensionsRequired` that we do not implement.
    #[error("extensionsRequired[{index}]: required extension {name} is not supported")]
    UnsupportedExtension {
        /// The extension's name, e.g. `KHR_draco_mesh_compression`.
        name: String,
        /// Its position in `extensionsRequired`.
        index: usize,
    },
    /// The binary glTF container is truncated or malformed.
    #[error("GLB container: {reason}")]
    Glb {
        /// What is wrong with the container.
        reason: String,
    },
    /// The JSON could not be parsed, or does not have the shape of a glTF document.
    #[error("JSON: {source}")]
    Json {
        /// The parser's error (with line and column).
        source: serde_json::Error,
    },
    /// The glTF document breaks a rule of the specification (found by the `gltf` crate's validation).
    #[error("{at}: {reason}")]
    Invalid {
        /// JSON path of the offending value.
        at: String,
        /// What is wrong.
        reason: String,
    },
    /// A URI that may not be followed (outside the scene folder, absolute, or remote).
    #[error("{at}: URI {uri:?} refused: {reason}")]
    ForbiddenUri {
        /// JSON path of the URI (`buffers[0].uri`).
        at: String,
        /// The URI as written in the file.
        uri: String,
        /// Why it is refused.
        reason: String,
    },
    /// A buffer or image file named by a URI could not be read.
    #[error("{at}: cannot read {path}: {source}")]
    MissingFile {
        /// JSON path of the URI.
        at: String,
        /// The resolved file path.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A `data:` URI that is not valid base64.
    #[error("{at}: bad data URI: {reason}")]
    DataUri {
        /// JSON path of the URI.
        at: String,
        /// What is wrong.
        reason: String,
    },
    /// A buffer shorter than its `byteLength`.
    #[error("buffers[{buffer}]: byteLength is {claimed} but only {actual} bytes are present")]
    BufferTooShort {
        /// Buffer index.
        buffer: usize,
        /// `byteLength` from the file.
        claimed: u64,
        /// Bytes actually available.
        actual: u64,
    },
    /// An accessor (or buffer view) reaches outside the bytes that back it.
    #[error("{at}: needs bytes up to {needed} but only {available} are available")]
    OutOfBounds {
        /// JSON path of the accessor or buffer view (`accessors[4]`, `accessors[4].sparse.indices`).
        at: String,
        /// One past the last byte the data would need.
        needed: u64,
        /// Bytes available.
        available: u64,
    },
    /// An accessor whose type or component type cannot be used where it is used.
    #[error("{at}: {reason}")]
    BadAccessor {
        /// JSON path of the use (`meshes[0].primitives[1].attributes.NORMAL`).
        at: String,
        /// What is wrong.
        reason: String,
    },
    /// A vertex index past the end of the vertex arrays.
    #[error("{at}: index {index} out of range ({vertices} vertices)")]
    IndexOutOfRange {
        /// JSON path of the indices (`meshes[2].primitives[0].indices`).
        at: String,
        /// The offending index.
        index: u64,
        /// Number of vertices.
        vertices: usize,
    },
    /// A TRIANGLES primitive whose index (or vertex) count is not a multiple of 3.
    #[error("{at}: {count} indices is not a multiple of 3")]
    IndexCount {
        /// JSON path of the primitive.
        at: String,
        /// The count.
        count: usize,
    },
    /// A NaN or infinite value where geometry or a transform needs a finite number.
    #[error("{at}: non-finite value {value}")]
    NonFinite {
        /// JSON path (`accessors[0]` element 3, `nodes[1].matrix`).
        at: String,
        /// The value.
        value: String,
    },
    /// A depth-of-field setting (SPEC §3) with the wrong type or out of range.
    #[error("camera {camera:?}: {key} = {value}: {reason}")]
    InvalidDof {
        /// Camera name.
        camera: String,
        /// The key (`aperture_fstop`, `EXT_camera_physical.fStop`, `--focus-distance`).
        key: String,
        /// The value as written.
        value: String,
        /// What is wrong.
        reason: String,
    },
    /// A motion-blur key of `scenes[i].extras` (SPEC §7) with the wrong type or out of range.
    #[error("scenes[{scene}].extras: {key} = {value}: {reason}")]
    InvalidSceneExtra {
        /// The scene's index.
        scene: usize,
        /// The key (`motion_blur_shutter`, `motion_blur_position`, ...).
        key: String,
        /// The value as written.
        value: String,
        /// What is wrong.
        reason: String,
    },
    /// A scene index that does not exist (`--scene N`).
    #[error("scene {index} does not exist (the file has {count})")]
    NoSuchScene {
        /// Requested index.
        index: usize,
        /// Number of scenes in the file.
        count: usize,
    },
    /// The node graph is not a forest (a node with two parents, or a cycle).
    #[error("nodes[{node}]: {reason}")]
    NodeGraph {
        /// The node where the problem was found.
        node: usize,
        /// What is wrong.
        reason: String,
    },
    /// Compressed geometry (`KHR_draco_mesh_compression`, `KHR_meshopt_compression` or
    /// `EXT_meshopt_compression`) that does not decode, or decodes to other sizes than its
    /// accessors state.
    #[error("{at}: {reason}")]
    Compressed {
        /// JSON path of the compressed data (`meshes[0].primitives[1].extensions.KHR_draco_mesh_compression`).
        at: String,
        /// What is wrong.
        reason: String,
    },
    /// `--camera` names no camera of the scene.
    #[error("no camera {wanted} in the scene (it has: {available})")]
    NoSuchCamera {
        /// The selector asked for (`name`, `N`, `node:J`).
        wanted: String,
        /// The scene's cameras, `N "name"` (`node:J` added when a camera has two nodes).
        available: String,
    },
    /// `--animation` names an animation the file does not have.
    #[error("no animation {wanted} in the file (it has: {available})")]
    NoSuchAnimation {
        /// The index or name asked for.
        wanted: String,
        /// The file's animations, `index "name"`.
        available: String,
    },
    /// `--variant` names a `KHR_materials_variants` variant the file does not have.
    #[error("no material variant {wanted} in the file (it has: {available})")]
    NoSuchVariant {
        /// The index or name asked for.
        wanted: String,
        /// The file's variants, `"name"`, or "none".
        available: String,
    },
    /// An image could not be decoded.
    #[error("images[{image}]: {source}")]
    Image {
        /// Image index.
        image: usize,
        /// The decoder's error.
        source: image::ImageError,
    },
    /// Decoding would take more memory than the budget ([`crate::LoadOptions::memory`]: the
    /// machine's memory unless `--max-memory` says otherwise).
    #[error("{at}: {source}")]
    OverBudget {
        /// What was being decoded (`images[3]`, `textures`, `meshes[0].primitives[1]...`).
        at: String,
        /// The sizes.
        source: aperture_budget::OverBudget,
    },
    /// The loader panicked: a value it cannot handle (with overflow checks, a size that
    /// wraps). A bug, reported as an error rather than a crash; the fuzzers still see it.
    #[error("the loader panicked ({message}): a bug, please report the file")]
    Panicked {
        /// The panic's message.
        message: String,
    },
}

/// The message a caught panic carried (`panic!` with a literal or a formatted string), or
/// nothing.
pub(crate) fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_default()
}
