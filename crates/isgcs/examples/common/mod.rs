//! Command-line flags shared by the regressor examples (`peers`, `unseen`).

use isgcs::regressor::RegressorParams;

/// The value after the flag `name`, or `default` when the flag is absent or unparsable.
pub fn arg<T: std::str::FromStr>(args: &[String], name: &str, default: T) -> T {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The value after the flag `name` when the flag is given.
fn given<T: std::str::FromStr>(args: &[String], name: &str) -> Option<T> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
}

/// [`RegressorParams`] with `cells` and `seed` and the defaults, overridden by the flags
/// `--mult μ`, `--ridge ρ`, `--lambda λ`, `--k k` (fixed when given) and `--metric`,
/// `--affine`, `--choose`, `--normalized` (0 or 1).
pub fn regressor_params(args: &[String], cells: usize, seed: u64) -> RegressorParams {
    let defaults = RegressorParams::default();
    let flag = |name: &str, default: bool| arg::<u8>(args, name, u8::from(default)) == 1;
    RegressorParams {
        max_cells: cells,
        seed,
        width_multiplier: given(args, "--mult"),
        ridge: given(args, "--ridge"),
        lambda: given(args, "--lambda"),
        topology_dim: given(args, "--k"),
        metric: flag("--metric", defaults.metric),
        affine: flag("--affine", defaults.affine),
        choose_basis: flag("--choose", defaults.choose_basis),
        normalized: flag("--normalized", defaults.normalized),
        ..defaults
    }
}

/// The problem size and selection flags: `--cells C` (300), `--rows N` (10 C), `--seed S`
/// (1), `--only NAME` (every problem whose name contains NAME).
pub struct Run {
    pub cells: usize,
    pub rows: usize,
    pub seed: u64,
    pub only: String,
}

impl Run {
    pub fn from_args(args: &[String]) -> Self {
        let cells = arg(args, "--cells", 300);
        Self {
            cells,
            rows: arg(args, "--rows", 10 * cells),
            seed: arg(args, "--seed", 1),
            only: arg(args, "--only", String::new()),
        }
    }
}
