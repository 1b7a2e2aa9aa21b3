//! Reference radiosity solvers that share no code with the growing-cells networks.
//!
//! So far: [`pointwise`], the path-traced pointwise reference of MATH.md §8 for 3-D scenes.

pub mod hierarchical;
pub mod pointwise;
