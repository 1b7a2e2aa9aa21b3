//! Incremental supervised growing cell structures: a generic function approximator (Bohn 2000, ch. 2).
