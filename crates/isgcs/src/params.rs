//! Training parameters with the dissertation's recommended values (fig. 4.17).

use serde::{Deserialize, Serialize};

/// Training parameters (fig. 4.17 gives the recommended ranges).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// ε_BMU: adaption strength of the best-matching unit (eq. 2.6; 0.01–0.05).
    pub eps_bmu: f64,
    /// ε_N: adaption strength of its neighbours (eq. 2.9 as corrected in docs/design/math.md; 0.001–0.009).
    pub eps_neighbour: f64,
    /// α: decay rate of the resource terms (eq. 2.15–2.18; 0.01–0.05).
    pub alpha: f64,
    /// η: learning rate of the output layer (eq. 2.8; 0.01–0.1).
    pub eta: f64,
    /// λ: steps between insertions (300–600).
    pub lambda: usize,
    /// φ: activation threshold of the inside test (definition 5; 0.4–0.6).
    pub phi: f64,
    /// ω: a cell is critical when its resource is at least ω times the mean (definition 6).
    pub omega: f64,
    /// Weight of the unsupervised (quantization) resource in the combined resource τ (sec. 2.4);
    /// 0 is the pure supervised resource.
    pub usl_weight: f64,
    /// Multiplier on the widths d_i (1 is the dissertation's eq. 2.10).
    pub width_multiplier: f64,
    /// Topological depth of [`crate::Isgcs::neighbourhood`] queries (sec. 2.6).
    pub locality_depth: usize,
    /// Normalized activations: Ψ(ξ) = Σ v_i Ω_i(ξ) / Σ Ω_i(ξ) instead of eq. 2.5's plain sum
    /// (a knob beyond the dissertation; `false` is eq. 2.5). The delta rule (eq. 2.8) then uses
    /// the normalized activations as its gradient.
    #[serde(default)]
    pub normalized: bool,
    /// κ: steps between deletion tests (sec. 2.4.2, fig. 2.9; the dissertation recommends
    /// 400–1000). 0 switches deletion off, which is the default: the defaults reproduce the
    /// network `gcr` was tuned on, which never deletes.
    #[serde(default)]
    pub kappa: usize,
    /// Use the extended resource τ^x_i = (τ^SL_i / h_i) · l̄_i^k (eq. 2.19 as corrected in
    /// docs/design/math.md §6: the mean error per hit times the cell's volume estimate, h_i the hits decayed
    /// like the resources, l̄_i the mean edge length, k̃ = k) for insertion and deletion instead
    /// of τ^SL + `usl_weight` · τ^USL. Off by default.
    #[serde(default)]
    pub extended_resource: bool,
    /// At insertion, redistribute output weights and resources by the Voronoi-volume ratios Γ of
    /// eq. 2.11–2.14, 2.20 and 2.21 (f̂_i = l̄_i^k̃ with k̃ = k, the topology's dimension):
    /// each neighbour j of the new cell r gives `Γ_j · v_j` (Γ_j < 0 when its volume shrinks) and
    /// r receives the sum, so Σ v and Σ τ over the neighbourhood are conserved. Off by default:
    /// the default rule (r takes the mean output of the split edge's ends and a third of their
    /// resources) is what `gcr` was tuned with.
    #[serde(default)]
    pub gamma_redistribution: bool,
    /// ε: every κ steps the cell with the lowest resource τ_i is deleted if τ_i < ε
    /// (sec. 2.4.2; fig. 2.9 says "exceeds", a typo per docs/design/math.md §6). The dissertation
    /// recommends 0.001–0.01 for its resource scale.
    #[serde(default)]
    pub epsilon: f64,
}

impl Params {
    /// The dissertation's defaults (fig. 4.17); identical to [`Params::default`].
    pub fn thesis() -> Self {
        Self::default()
    }

    /// A preset tuned for approximation accuracy on smooth functions (measured in docs/design/isgcs.md):
    /// normalized activations and Gaussians twice as wide as eq. 2.10. Use it together with
    /// [`crate::Isgcs::fit_outputs`], the least-squares polish of the output layer after
    /// growth; the delta rule alone converges slowly on the overlapping Gaussians. λ stays at
    /// 300: with λ = 100 the cells had too few steps to spread between insertions, widths
    /// ranged over two orders of magnitude and the least-squares fit overfitted.
    pub fn accurate() -> Self {
        Self {
            width_multiplier: 2.0,
            normalized: true,
            ..Self::default()
        }
    }
}

impl Default for Params {
    fn default() -> Self {
        Self {
            eps_bmu: 0.03,
            eps_neighbour: 0.005,
            alpha: 0.03,
            eta: 0.05,
            lambda: 300,
            phi: 0.5,
            omega: 1.5,
            usl_weight: 0.0,
            width_multiplier: 1.0,
            locality_depth: 2,
            normalized: false,
            kappa: 0,
            epsilon: 0.0,
            extended_resource: false,
            gamma_redistribution: false,
        }
    }
}
