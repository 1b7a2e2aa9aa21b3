//! Reference radiosity solvers: pointwise path tracing, classical and hierarchical radiosity.
