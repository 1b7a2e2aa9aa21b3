//! One call from a scene to a solution: builds the domain and both networks, trains, and returns
//! what the outputs need.

use crate::config::SolveConfig;
use crate::domain::Domain;
use crate::solver::{Progress, Trained, train};
use isgcs::{Isgcs, Params};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thiserror::Error;

/// Why a solve could not run.
#[derive(Debug, Error)]
pub enum SolveError {
    /// A setting is out of range.
    #[error(transparent)]
    Config(#[from] crate::config::ConfigError),
    /// The networks could not be created.
    #[error("network: {0}")]
    Network(#[from] isgcs::IsgcsError),
    /// The kernel projection kept breaking the maximum-principle bound on B.
    #[error("numerically unstable solve: {0}")]
    Unstable(String),
}

/// Creates the kernel network (n = 2·dim, k = 4 in 3-D / 2 in Flatland, m = bands) and the
/// shading network (n = dim, k = 2 / 1, m = dim: the normal), each starting from a simplex on
/// random samples of its input domain.
pub fn make_networks(domain: &Domain, config: &SolveConfig) -> Result<(Isgcs, Isgcs), SolveError> {
    let dim = domain.dim();
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed ^ 0x5EED);
    let pd = domain.param_dim();
    let mut input = Vec::new();
    let k_kernel = if dim == 3 { 4 } else { 2 };
    let k_shading = dim - 1;
    let mut draw = |n: usize, rng: &mut ChaCha8Rng, receiver_only: bool| -> Vec<Vec<f64>> {
        (0..n)
            .map(|_| {
                let u: Vec<f64> = (0..pd).map(|_| rng.random::<f64>()).collect();
                domain.endpoints(&u).input(&mut input);
                // `input` is (x, y) with `dim` coordinates each.
                if receiver_only {
                    input[dim..].to_vec()
                } else {
                    input.clone()
                }
            })
            .collect()
    };
    let kernel_init = draw(k_kernel + 1, &mut rng, false);
    let shading_init = draw(k_shading + 1, &mut rng, true);
    let params = Params {
        lambda: config.lambda,
        ..Params::default()
    };
    let kernel = Isgcs::new(params, 2 * dim, domain.bands(), k_kernel, kernel_init)?;
    let shading = Isgcs::new(params, dim, dim, k_shading, shading_init)?;
    Ok((kernel, shading))
}

/// Validates the configuration, builds the networks and trains them (figs. 1.2, 3.1, B.1).
pub fn solve(
    domain: &Domain,
    config: &SolveConfig,
    observer: &mut dyn FnMut(&Progress),
) -> Result<Trained, SolveError> {
    config.validate()?;
    let (mut kernel, mut shading) = make_networks(domain, config)?;
    train(domain, &mut kernel, &mut shading, config, observer)
}
