//! Writers for a solved scene: PNG image, binary glTF, PLY, and the tone mapping they share.

pub mod flatland;
pub mod glb;
pub mod ply;
pub mod raster;
pub mod tonemap;
