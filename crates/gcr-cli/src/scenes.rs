//! `gcr scenes`: the built-in scene names.

/// Prints the built-in scenes and the generated families, one per line.
pub fn run() -> anyhow::Result<()> {
    for name in scene_sampler::BUILTIN_NAMES {
        println!("{name}");
    }
    println!(
        "random-boxes-<N>            (generated: the Cornell box filled with small random boxes, about N triangles)"
    );
    println!("tessellated-cornell-<N>     (generated: the Cornell box cut into about N triangles)");
    Ok(())
}
