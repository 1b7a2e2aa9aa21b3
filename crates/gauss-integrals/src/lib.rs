//! Closed-form Gaussian integrals over segments and triangles, adaptive cubature, and the
//! orthonormalization of a Gaussian base (Bohn 2000, ch. 3, with the corrections of docs/design/math.md).
//!
//! A Gaussian here is `exp(−a|x − c|²)` with `a = 1/d²` (eq. 2.1; `d` is not the standard
//! deviation). Everything takes plain `[f64; 3]` points: this crate knows nothing of scenes or
//! networks.
//!
//! - [`closed_form`], [`wedge`]: exact integrals over segments and triangles (docs/design/math.md §2);
//! - [`cubature`]: adaptive cubature, the reference of the tests;
//! - [`criteria`]: the error estimates of sec. 3.9.4 and the decision of fig. 3.6;
//! - [`gram`](mod@gram): sparse Gram matrices of Gaussian bases on triangulated or segmented domains
//!   (zero rules, flat closed form eq. 3.52, exact element sums);
//! - [`orthonormal`]: the Cholesky orthonormalization (docs/design/math.md §5);
//! - [`transfer`]: the factorized transfer coefficients of docs/design/math.md §3.
//!
//! ```
//! use gauss_integrals::{triangle, plane};
//! // A huge triangle around the centre integrates to the whole-plane value π/a.
//! let big = [[-1e3, -1e3, 0.0], [1e3, -1e3, 0.0], [0.0, 1e3, 0.0]];
//! let i = triangle([0.0, 0.0, 0.0], 2.0, big[0], big[1], big[2]);
//! assert!((i - plane(2.0, 0.0)).abs() < 1e-12);
//! ```

pub mod closed_form;
pub mod criteria;
pub mod cubature;
pub mod gram;
pub mod orthonormal;
pub mod transfer;
pub mod wedge;

pub use closed_form::{
    ConvexPolygon, line, plane, product, quad, quad_fast, segment, triangle, triangle_fast,
    triangle_reference,
};
pub use cubature::{Cubature, triangle_cubature};
pub use gram::{
    Dim, Domain, Gaussian, Gram, GramConfig, GramError, Sparse, gram, gram_with, support_radius,
};
pub use orthonormal::{Orthonormal, classical_gram_schmidt};
pub use transfer::{Factors, KernelGaussian};
