//! Closed-form Gaussian integrals over segments and triangles, adaptive cubature, Gram matrices and orthonormalization (Bohn 2000, ch. 3).
