//! The `gcr` command-line program.

fn main() -> anyhow::Result<()> {
    anyhow::bail!("gcr: the solver is not implemented yet")
}
