//! Growing Cells Radiosity: radiosity on evolving networks (Bohn 2000).
//!
//! The solver learns the light flow K(x,y)·B(x) with a growing-cell-structures network (the
//! *kernel network*, [`isgcs`]), meshes the surfaces with a second one (the *shading network*),
//! and integrates between them in closed form ([`gauss_integrals`]).

pub mod cluster;
pub mod config;
pub mod domain;
pub mod element;
pub mod fem;
pub mod gather;
pub mod mesh;
pub mod metrics;
pub mod network;
pub mod output;
pub mod pipeline;
pub mod projection;
pub mod retriangulate;
pub mod shading;
pub mod shooting;
pub mod solve;
pub mod spatial;

/// The README's code, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
