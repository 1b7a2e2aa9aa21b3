//! Errors of scene loading, validation and probe parsing.

use std::path::PathBuf;

/// Everything that can go wrong while loading or validating a scene or a probe file.
///
/// Every variant names its source (a file path, or `builtin:<name>` for built-in scenes) and, where it
/// applies, the face (triangle or segment index in the file's order) or line, so that the message alone
/// tells the user what to fix. Bad input never panics.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// An albedo texture that cannot be read or decoded.
    #[error("texture {name}: {message}")]
    Texture {
        /// The texture's file or name.
        name: String,
        /// What is wrong.
        message: String,
    },
    /// A file a scene names (a glTF buffer or image, an OBJ's material library or texture) that lies
    /// outside the scene file's folder: refused unless [`crate::LoadOptions::allow_outside`]. The
    /// message is the same whether or not the file exists, and quotes nothing of it.
    #[error(
        "{source_name}: {what} refers to a file outside the scene's folder: {uri}; pass \
         --allow-outside-files to allow it"
    )]
    OutsideFolder {
        /// The scene file (with the line, where known).
        source_name: String,
        /// What names the file (e.g. `buffer 0`, `` `mtllib` ``).
        what: String,
        /// The URI or file name as the scene wrote it.
        uri: String,
    },
    /// A path that is not a regular file (a device such as `/dev/zero`, a FIFO, a directory):
    /// refused before it is opened.
    #[error("{path}: not a regular file (a device, FIFO or directory): refused")]
    NotRegularFile {
        /// The path.
        path: PathBuf,
    },
    /// A file larger than the bound on the size of each file read
    /// ([`crate::LoadOptions::max_file_bytes`]).
    #[error(
        "{path}: larger than the bound of {limit} bytes per file (raise it with --max-file-mib, or \
         LoadOptions::max_file_bytes)"
    )]
    FileTooLarge {
        /// The file.
        path: PathBuf,
        /// The bound in bytes.
        limit: u64,
    },
    /// A texture whose decoded size (12 bytes per texel: linear RGB in f32), added to the scene's
    /// other textures, exceeds the bound on texture memory ([`crate::LoadOptions::max_texture_bytes`]);
    /// found from the image's header, before decoding.
    #[error(
        "texture {name}: {width}×{height} texels would take {bytes} bytes decoded, over the bound of \
         {limit} bytes on texture memory ({used} bytes already taken by the scene's other textures; \
         raise it with --max-texture-mib, or LoadOptions::max_texture_bytes)"
    )]
    TextureMemory {
        /// The texture's file or name.
        name: String,
        /// Width in texels (from the header).
        width: u32,
        /// Height in texels.
        height: u32,
        /// Its decoded size in bytes.
        bytes: u64,
        /// The decoded size of the textures loaded before it.
        used: u64,
        /// The bound in bytes.
        limit: u64,
    },
    /// The file is not well-formed in its format.
    #[error("{source_name}: malformed: {message}")]
    Parse {
        /// The file (or `builtin:<name>`).
        source_name: String,
        /// What is wrong.
        message: String,
    },
    /// The file extension names no supported format.
    #[error("{path}: unsupported scene format (expected .obj, .gltf, .glb or .json)")]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
    /// A built-in scene name that does not exist (and no file of that name either).
    #[error("unknown built-in scene `{name}`{hint} (known: {known})")]
    UnknownBuiltin {
        /// The name asked for.
        name: String,
        /// ` — did you mean `cornell-box`?` when a known name is close, else empty.
        hint: String,
        /// The known names, comma-separated.
        known: String,
    },
    /// An OBJ file's `mtllib` names a material library that cannot be read.
    #[error("{source_name}:{line}: material library `{path}` cannot be read: {source}", path = path.display())]
    MaterialLibrary {
        /// The OBJ file.
        source_name: String,
        /// 1-based line of the `mtllib` statement (0 if unknown).
        line: usize,
        /// The path tried (the `mtllib` name relative to the OBJ file's directory).
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A `usemtl` names a material that no material library defines.
    #[error("{source_name}:{line}: `usemtl {name}`: no material of that name is defined ({known})")]
    UndefinedMaterial {
        /// The OBJ file.
        source_name: String,
        /// 1-based line of the `usemtl` statement.
        line: usize,
        /// The material name.
        name: String,
        /// The defined names, or why there are none.
        known: String,
    },
    /// A material whose reflectance or emission is negative or not finite.
    #[error("{source_name}: material `{material}`: {message}")]
    BadMaterial {
        /// The file (OBJ, MTL, glTF or Flatland JSON).
        source_name: String,
        /// The material's name (glTF: its name or `material <index>`; Flatland: the segment).
        material: String,
        /// What is wrong, with the value.
        message: String,
    },
    /// Two coincident faces of the same orientation but different materials: which one a ray sees would
    /// be decided by rounding, so the answer would be arbitrary.
    #[error(
        "{source_name}: face {face} (object `{object}`) coincides with face {other} (object `{other_object}`) \
         but has a different material: remove one of them"
    )]
    ConflictingDuplicate {
        /// The file.
        source_name: String,
        /// The later face (load order).
        face: usize,
        /// Its object.
        object: String,
        /// The earlier face it coincides with.
        other: usize,
        /// That face's object.
        other_object: String,
    },
    /// A vertex coordinate, normal or attribute is NaN or infinite.
    #[error("{source_name}: face {face}: non-finite {what}")]
    NonFinite {
        /// The file.
        source_name: String,
        /// Face index (in load order, before degenerate faces are dropped).
        face: usize,
        /// Which quantity (e.g. `vertex coordinate`, `emission`).
        what: String,
    },
    /// A reflectance outside `[0, 1)`: energy would not be conserved (or would be negative).
    #[error("{source_name}: face {face}: reflectance {value} in band {band} is outside [0, 1)")]
    ReflectanceOutOfRange {
        /// The file.
        source_name: String,
        /// Face index (load order).
        face: usize,
        /// The colour band (0 = r, 1 = g, 2 = b).
        band: usize,
        /// The offending value.
        value: f64,
    },
    /// A negative emission.
    #[error("{source_name}: face {face}: negative emission {value} in band {band}")]
    NegativeEmission {
        /// The file.
        source_name: String,
        /// Face index (load order).
        face: usize,
        /// The colour band.
        band: usize,
        /// The offending value.
        value: f64,
    },
    /// Every face was degenerate (or the file had none).
    #[error("{source_name}: no usable faces ({dropped} degenerate faces dropped)")]
    NoFaces {
        /// The file.
        source_name: String,
        /// How many degenerate faces were dropped.
        dropped: usize,
    },
    /// Nothing gives light: no face emits and no other light is given (the radiosity solution
    /// would be zero everywhere).
    #[error(
        "{source_name}: nothing gives light: no face emits (set Ke in the MTL, emissiveFactor in glTF, \
         `emission` in Flatland JSON) and no light is given (3-D scenes: --sun AZ,EL,LUX, --sky MODEL:LUX, \
         --env MAP.hdr, --point-light X,Y,Z,CD or a lighting file --lights FILE; docs/guide/lights.md)"
    )]
    NoEmitter {
        /// The file.
        source_name: String,
    },
    /// A lighting description (program options, a lighting file) that gives no valid light.
    #[error("lighting: {message}")]
    Lighting {
        /// What is wrong, naming the value.
        message: String,
    },
    /// A probe line that is not `x y z nx ny nz` (3-D) or `x y nx ny` (Flatland).
    #[error("{source_name}:{line}: bad probe: {message}")]
    ProbeParse {
        /// The probe file.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A probe farther than the tolerance from every surface facing its normal.
    #[error(
        "{source_name}:{line}: probe is {distance:.3e} from the nearest surface facing its normal (tolerance {tolerance:.3e})"
    )]
    ProbeOffSurface {
        /// The probe file.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// Distance to the nearest compatible surface (infinite if none faces the probe's normal).
        distance: f64,
        /// The tolerance used.
        tolerance: f64,
    },
    /// A scene whose size (bounding-box diagonal) is outside what the f32 BVH can represent: stray vertices
    /// or wrong units.
    #[error(
        "{source_name}: the scene is {diagonal:e} units across, outside [1e-9, 1e12]: check the units and for \
         stray vertices"
    )]
    ExtentOutOfRange {
        /// The file.
        source_name: String,
        /// The bounding-box diagonal.
        diagonal: f64,
    },
    /// A 3-D operation on a Flatland scene or vice versa.
    #[error("{0}")]
    WrongDimension(String),
    /// Light options that do not fit the scene or each other (lights for a Flatland scene, sky
    /// portals without a sky: [`crate::LightOptions::light`]).
    #[error("{0}")]
    LightOptions(String),
}

/// Shorthand for results of this crate.
pub type Result<T, E = SceneError> = std::result::Result<T, E>;
