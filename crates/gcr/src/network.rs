//! What the solver needs from a growing-cell-structures network, as a small trait.
//!
//! The kernel network and the shading network are both [`isgcs`] networks; the solver talks to
//! them through this trait so that the orchestration reads as the dissertation's main loop
//! (fig. B.1) and does not depend on the approximator's internals.

/// A growing-cell-structures network as the radiosity solver drives it.
pub trait GrowingNetwork {
    /// Presents one training sample (unsupervised step on `input`, supervised step towards
    /// `target`), including the periodic insertion and deletion of cells.
    fn train(&mut self, input: &[f64], target: &[f64]);
    /// Number of cells.
    fn cell_count(&self) -> usize;
    /// Counts every insertion since the network was created.
    fn insertions(&self) -> u64;
    /// Centre w_i of cell `i`.
    fn centre(&self, i: usize) -> &[f64];
    /// Width d_i of cell `i` (eq. 2.10).
    fn width(&self, i: usize) -> f64;
    /// Output weights v_i of cell `i`.
    fn output(&self, i: usize) -> &[f64];
    /// The k-simplices, as cell indices (k + 1 used; unused slots are `usize::MAX`).
    fn simplices(&self) -> Vec<[usize; 3]>;
    /// Whether `input` lies in a critical region (definition 7, eq. 2.23): near high-resource
    /// cells or outside the network.
    fn is_critical(&self, input: &[f64]) -> bool;
    /// The network output Ψ(input).
    fn predict(&self, input: &[f64], out: &mut [f64]);
    /// Switches insertion and deletion of cells on or off (training of the existing cells goes
    /// on either way): the solver freezes a network's size once its budget is reached.
    fn set_growing(&mut self, on: bool);
}

impl GrowingNetwork for isgcs::Isgcs {
    fn train(&mut self, input: &[f64], target: &[f64]) {
        isgcs::Isgcs::train(self, input, target, None);
    }
    fn cell_count(&self) -> usize {
        self.len()
    }
    fn insertions(&self) -> u64 {
        isgcs::Isgcs::insertions(self)
    }
    fn centre(&self, i: usize) -> &[f64] {
        isgcs::Isgcs::centre(self, i)
    }
    fn width(&self, i: usize) -> f64 {
        isgcs::Isgcs::width(self, i)
    }
    fn output(&self, i: usize) -> &[f64] {
        isgcs::Isgcs::output(self, i)
    }
    fn simplices(&self) -> Vec<[usize; 3]> {
        isgcs::Isgcs::simplices(self)
            .iter()
            .map(|s| {
                let mut out = [usize::MAX; 3];
                for (o, v) in out.iter_mut().zip(s) {
                    *o = *v as usize;
                }
                out
            })
            .collect()
    }
    fn is_critical(&self, input: &[f64]) -> bool {
        isgcs::Isgcs::is_critical(self, input)
    }
    fn predict(&self, input: &[f64], out: &mut [f64]) {
        isgcs::Isgcs::predict(self, input, out)
    }
    fn set_growing(&mut self, on: bool) {
        isgcs::Isgcs::set_growing(self, on)
    }
}
