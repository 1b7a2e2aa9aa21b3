//! `gcr merge`: the partial probe outputs of `gcr solve --shard I/N` joined into the single
//! run's probe output (`gcr::output::shards`), written all or nothing.

use crate::args::MergeArgs;
use anyhow::{Context, Result};
use gcr::output::{StagedFiles, check_target, shards};

/// Runs `gcr merge`.
pub fn run(args: &MergeArgs) -> Result<()> {
    check_target(&args.probe_out, "probe", None)?;
    let parts = shards::read_parts(&args.parts)?;
    let merged = shards::merge(&parts).context("merging the shards")?;
    match merged.kind {
        shards::Kind::Lightmap => anyhow::bail!(
            "these are a lightmap's shards: they are merged by the solve that lays the atlas \
             out, `gcr solve SCENE --lightmap OUT.glb … --from-shards PARTS…` with the shards' \
             options (docs/guide/lightmaps.md, \"Sharded bakes\")"
        ),
        shards::Kind::Image => anyhow::bail!(
            "these are an image's shards: they are merged by the solve that writes the image, \
             `gcr solve SCENE --image OUT.exr … --from-shards PARTS…` with the shards' options \
             (docs/guide/images.md, \"Sharded images\")"
        ),
        shards::Kind::Probes => {}
    }
    let mut staged = StagedFiles::new();
    staged.write_bytes(&args.probe_out, merged.text.as_bytes())?;
    staged.commit()?;
    eprintln!(
        "merged {} shards: {} probes to {}",
        parts.len(),
        merged.text.lines().count(),
        args.probe_out.display()
    );
    Ok(())
}
