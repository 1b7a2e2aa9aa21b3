//! `gcr merge`: the partial probe outputs of `gcr solve --shard I/N` joined into the single
//! run's probe output (`gcr::output::shards`), written all or nothing.

use crate::args::MergeArgs;
use anyhow::{Context, Result};
use gcr::output::{StagedFiles, check_target, shards};

/// Runs `gcr merge`.
pub fn run(args: &MergeArgs) -> Result<()> {
    check_target(&args.probe_out, "probe", None)?;
    let limit = scene_sampler::LoadOptions::default().max_file_bytes;
    let parts = (args.parts.iter())
        .map(|p| {
            let name = p.display().to_string();
            let bytes = scene_sampler::confine::read_regular_file(p, limit)?;
            let text = String::from_utf8(bytes)
                .with_context(|| format!("{name}: not text (a partial probe output is UTF-8)"))?;
            Ok((name, text))
        })
        .collect::<Result<Vec<_>>>()?;
    let merged = shards::merge(&parts).context("merging the shards")?;
    let mut staged = StagedFiles::new();
    staged.write_bytes(&args.probe_out, merged.as_bytes())?;
    staged.commit()?;
    eprintln!(
        "merged {} shards: {} probes to {}",
        parts.len(),
        merged.lines().count(),
        args.probe_out.display()
    );
    Ok(())
}
