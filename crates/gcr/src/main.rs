//! The `gcr` command-line program: `gcr scenes`, `gcr solve`.

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use gcr::output::tonemap::Exposure;
use gcr::{
    Domain, Emitters, GatherMode, GatherSamples, NetworkTarget, OutputFit, RetriangulateLimits,
    SolveConfig, SurfaceClusters, output_mesh, radiosity_at_points,
};
use scene_sampler::{AnyScene, FlatKernelSampler, KernelSampler, SceneBvh};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "gcr",
    version,
    about = "Growing Cells Radiosity: radiosity on evolving networks (Bohn 2000)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
#[allow(clippy::large_enum_variant)] // parsed once; boxing would only obscure the clap derive
enum Command {
    /// List the built-in scenes.
    Scenes,
    /// Solve a scene (a file: .obj, .gltf, .glb, Flatland .json; or a built-in name).
    Solve {
        /// Scene file or built-in name.
        scene: String,
        /// Kernel network cell budget ("links").
        #[arg(long, default_value_t = SolveConfig::default().kernel_cells)]
        cells: usize,
        /// Shading network cell budget.
        #[arg(long)]
        shading_cells: Option<usize>,
        /// Training time budget in seconds.
        #[arg(long)]
        time_budget: Option<f64>,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Output gather: base, kernel or rays.
        #[arg(long, default_value = "rays")]
        gather: GatherMode,
        /// Kernel output layer: `projection` (Galerkin projection of K·s on shot rays) or
        /// `delta-rule` (the dissertation's eq. 2.8).
        #[arg(long, default_value = "projection")]
        output_fit: OutputFit,
        /// What the kernel network learns (with the projection it only places the cells):
        /// `clamped-kernel` (K·s with G's 1/r² clamped at 5 % of the scene's diagonal),
        /// `kernel-value` (the dissertation's K·s, which crowds cells into the edges where K is
        /// singular) or `sample-weight` (each shot ray's importance weight ρ·s/p_x).
        #[arg(long, default_value = "clamped-kernel")]
        network_target: NetworkTarget,
        /// Ray gather: shadow rays and cosine rays per point (each). More rays lower the gather's
        /// own noise (two-blockers, 200 points: 6.2 % at 64, 4.4 % at 256, 3.9 % at 4096) at a
        /// proportional cost.
        #[arg(long, default_value_t = GatherSamples::default().direct)]
        gather_rays: usize,
        /// Train the shading network and build its base even when the gather does not read it
        /// (by default they are skipped: same result, less time).
        #[arg(long)]
        keep_base: bool,
        /// Facing masks on the projected kernel's Gaussians: each lives only on surfaces facing
        /// like the samples it was fitted to, so light does not blur across edges (sharper kernel
        /// gather on cluttered scenes, mass lost along edges of smooth fields).
        #[arg(long)]
        kernel_facing: bool,
        /// Surfaces with at least this many elements get a cluster tree for the FEM integrals
        /// (nodes stand in for their elements where a Gaussian cannot resolve them).
        #[arg(long, default_value_t = SurfaceClusters::default().min_elements)]
        cluster_min_elements: usize,
        /// Cluster criterion θ: a node replaces its elements when a·R² ≤ θ (0: exact).
        #[arg(long, default_value_t = SurfaceClusters::default().theta)]
        cluster_theta: f64,
        /// PNG image from the scene's camera.
        #[arg(long)]
        image: Option<PathBuf>,
        /// Flatland only: PNG of the light flow over the kernel domain (s of the sender to the
        /// right, t of the receiver upwards; fig. 4.1b): the sampled K·s on the left, the kernel
        /// network's Ψ on the right, dark = large; the training rays marked red on the right.
        #[arg(long)]
        kernel_image: Option<PathBuf>,
        /// Binary glTF mesh with vertex colours.
        #[arg(long)]
        mesh: Option<PathBuf>,
        /// PLY mesh with radiosity per vertex.
        #[arg(long)]
        ply: Option<PathBuf>,
        /// Probe points (`x y z nx ny nz` per line; Flatland `x y nx ny`).
        #[arg(long, requires = "probe_out")]
        probes: Option<PathBuf>,
        /// Where to write radiosity at the probes (`r g b` per line).
        #[arg(long, requires = "probes")]
        probe_out: Option<PathBuf>,
        /// JSON metrics.
        #[arg(long)]
        metrics: Option<PathBuf>,
        /// No progress output.
        #[arg(long)]
        quiet: bool,
    },
    /// The pointwise path-traced reference (`baselines`) at probe points: B per probe with its
    /// standard error on stderr.
    Reference {
        /// Scene file or built-in name.
        scene: String,
        /// Probe points (`x y z nx ny nz` per line; Flatland `x y nx ny`).
        #[arg(long)]
        probes: PathBuf,
        /// Where to write B at the probes (`r g b` per line; Flatland grey: `b`).
        #[arg(long)]
        probe_out: PathBuf,
        /// Target relative standard error per probe and band.
        #[arg(long, default_value_t = 0.01)]
        rel_error: f64,
        /// Path cap per probe.
        #[arg(long, default_value_t = 1_000_000)]
        max_paths: usize,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn run() -> Result<()> {
    match Cli::parse().command {
        Command::Scenes => {
            for name in scene_sampler::BUILTIN_NAMES {
                println!("{name}");
            }
            println!(
                "random-boxes-<N>            (generated: the Cornell box filled with small random boxes, about N triangles)"
            );
            println!(
                "tessellated-cornell-<N>     (generated: the Cornell box cut into about N triangles)"
            );
            Ok(())
        }
        Command::Reference {
            scene,
            probes,
            probe_out,
            rel_error,
            max_paths,
            seed,
        } => reference(&scene, &probes, &probe_out, rel_error, max_paths, seed),
        Command::Solve {
            scene,
            cells,
            shading_cells,
            time_budget,
            seed,
            gather,
            output_fit,
            network_target,
            gather_rays,
            keep_base,
            kernel_facing,
            cluster_min_elements,
            cluster_theta,
            image,
            kernel_image,
            mesh,
            ply,
            probes,
            probe_out,
            metrics,
            quiet,
        } => {
            let config = SolveConfig {
                kernel_cells: cells,
                shading_cells: shading_cells.unwrap_or((cells / 2).max(3)),
                time_budget,
                seed,
                gather,
                output_fit,
                network_target,
                gather_samples: GatherSamples {
                    direct: gather_rays,
                    indirect: gather_rays,
                },
                skip_unused_base: !keep_base,
                kernel_facing,
                surface_clusters: SurfaceClusters {
                    min_elements: cluster_min_elements,
                    theta: cluster_theta,
                },
                ..SolveConfig::default()
            };
            config.validate()?;
            let start = Instant::now();
            let loaded = scene_sampler::load_or_builtin(&scene)
                .with_context(|| format!("loading scene `{scene}`"))?;
            for w in loaded.warnings() {
                eprintln!("warning: {w}");
            }
            match loaded {
                AnyScene::ThreeD(s) => {
                    if kernel_image.is_some() {
                        bail!(
                            "--kernel-image needs a Flatland scene (the 3-D kernel has four \
                             parameters); `{scene}` is a 3-D scene"
                        );
                    }
                    let bvh = SceneBvh::new(&s);
                    let domain = Domain::ThreeD(KernelSampler::new(&s, &bvh));
                    solve_and_write(
                        &domain, &scene, &config, image, None, mesh, ply, probes, probe_out,
                        metrics, quiet, start,
                    )
                }
                AnyScene::Flatland(s) => {
                    if mesh.is_some() || ply.is_some() {
                        bail!("--mesh and --ply need a 3-D scene; `{scene}` is a Flatland scene");
                    }
                    let domain = Domain::Flat(FlatKernelSampler::new(&s));
                    solve_and_write(
                        &domain,
                        &scene,
                        &config,
                        image,
                        kernel_image,
                        None,
                        None,
                        probes,
                        probe_out,
                        metrics,
                        quiet,
                        start,
                    )
                }
            }
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn solve_and_write(
    domain: &Domain,
    scene_name: &str,
    config: &SolveConfig,
    image: Option<PathBuf>,
    kernel_image: Option<PathBuf>,
    mesh_path: Option<PathBuf>,
    ply: Option<PathBuf>,
    probes: Option<PathBuf>,
    probe_out: Option<PathBuf>,
    metrics_path: Option<PathBuf>,
    quiet: bool,
    start: Instant,
) -> Result<()> {
    let mut observer = |p: &gcr::Progress| {
        if !quiet {
            // The FEM steps' Gram matrices grow like cells² and dominate large budgets, so the
            // remaining time is extrapolated quadratically in the cell count.
            let done = p.kernel_cells as f64 / p.kernel_budget.max(1) as f64;
            let eta = if (0.1..1.0).contains(&done) {
                format!("  ETA ~{:.0} s", p.elapsed * (1.0 / (done * done) - 1.0))
            } else {
                String::new()
            };
            eprint!(
                "\r{:>8} kernel {:>5}/{} cells  shading {:>4}  samples {:>6}  FEM {:>3}  {:>6.1} s{eta}   ",
                p.phase,
                p.kernel_cells,
                p.kernel_budget,
                p.shading_cells,
                p.samples,
                p.fem_steps,
                p.elapsed
            );
        }
    };
    let trained = gcr::solve(domain, config, &mut observer)?;
    if !quiet {
        eprintln!();
    }
    let mut metrics = trained.metrics.clone();
    metrics.scene = scene_name.to_string();
    metrics.gather = config.gather.name().to_string();
    metrics.scene_elements = domain.elements().len();
    let tg = Instant::now();
    let emitters = Emitters::new(domain);
    if let (Some(input), Some(output)) = (probes, probe_out) {
        let text = probe_values(domain, &trained, &emitters, config, &input)?;
        std::fs::write(&output, text).with_context(|| format!("writing {}", output.display()))?;
    }
    if let Some(scene) = domain.scene_3d() {
        if image.is_some() || mesh_path.is_some() || ply.is_some() {
            let (mesh, share) =
                output_mesh(domain, &trained, config, RetriangulateLimits::default())?;
            metrics.network_share = share;
            metrics.output_vertices = mesh.vertex_count();
            metrics.output_triangles = mesh.triangle_count();
            metrics.seconds.gather += tg.elapsed().as_secs_f64();
            let to = Instant::now();
            let lit: Vec<[f64; 3]> = mesh
                .triangles
                .iter()
                .zip(&mesh.face_of_triangle)
                .filter(|(_, f)| scene.faces[**f as usize].emission.is_zero())
                .map(|(t, _)| mesh.radiosity[t[0] as usize])
                .collect();
            let exposure = Exposure::auto(lit);
            if let Some(path) = image {
                let cam = gcr::output::raster::PinholeCamera {
                    eye: scene.camera.eye,
                    target: scene.camera.target,
                    up: scene.camera.up,
                    fov_y_degrees: scene.camera.fov_y_deg,
                };
                let (w, h) = (512, 512);
                let px = gcr::output::raster::render(&mesh, &cam, &exposure, w, h, 2);
                image::RgbImage::from_raw(w, h, px)
                    .context("image buffer")?
                    .save(&path)
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            if let Some(path) = mesh_path {
                let f = std::fs::File::create(&path)
                    .with_context(|| format!("creating {}", path.display()))?;
                gcr::output::glb::write_glb(&mesh, &exposure, std::io::BufWriter::new(f))?;
            }
            if let Some(path) = ply {
                let f = std::fs::File::create(&path)
                    .with_context(|| format!("creating {}", path.display()))?;
                gcr::output::ply::write_ply(&mesh, &exposure, std::io::BufWriter::new(f))?;
            }
            metrics.seconds.output += to.elapsed().as_secs_f64();
        }
    } else if let (Some(path), Some(flat)) = (image, domain.scene_flat()) {
        flatland_image(domain, &trained, &emitters, config, flat, &path)?;
    }
    if let (Some(path), Domain::Flat(sampler)) = (kernel_image, domain) {
        flatland_kernel_image(domain, sampler, &trained, &path)?;
    }
    metrics.seconds.total = start.elapsed().as_secs_f64();
    metrics.peak_memory_bytes = gcr::peak_memory_bytes();
    if let Some(path) = metrics_path {
        std::fs::write(&path, serde_json::to_string_pretty(&metrics)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if !quiet {
        eprintln!(
            "done: {} kernel cells, {} shading cells, {} FEM steps, {:.1} s",
            metrics.kernel_cells, metrics.shading_cells, metrics.fem_steps, metrics.seconds.total
        );
    }
    Ok(())
}

fn probe_values(
    domain: &Domain,
    trained: &gcr::Trained,
    emitters: &Emitters,
    config: &SolveConfig,
    path: &PathBuf,
) -> Result<String> {
    let mut out = String::new();
    let grey = domain.bands() == 1;
    let mut line = |i: usize, b: [f64; 3]| {
        if grey && domain.dim() == 2 {
            out.push_str(&format!("{}\n", b[0]));
        } else {
            out.push_str(&format!("{} {} {}\n", b[0], b[1], b[2]));
        }
        let _ = i;
    };
    let points: Vec<(glam::DVec3, glam::DVec3, u32)> = match domain {
        Domain::ThreeD(k) => {
            let probes = scene_sampler::read_probes(path)?;
            let points = k.scene.snap_probes(&probes, &path.display().to_string())?;
            points.iter().map(|p| (p.point, p.normal, p.face)).collect()
        }
        Domain::Flat(k) => {
            let probes = scene_sampler::read_flat_probes(path)?;
            let points = k.scene.snap_probes(&probes, &path.display().to_string())?;
            points
                .iter()
                .map(|p| {
                    let y = glam::DVec3::new(p.point.x, p.point.y, 0.0);
                    let n = glam::DVec3::new(p.normal.x, p.normal.y, 0.0);
                    (y, n, p.segment)
                })
                .collect()
        }
    };
    for (i, g) in radiosity_at_points(domain, trained, emitters, config, &points)?
        .iter()
        .enumerate()
    {
        line(i, g.radiosity);
    }
    Ok(out)
}

fn flatland_image(
    domain: &Domain,
    trained: &gcr::Trained,
    emitters: &Emitters,
    config: &SolveConfig,
    flat: &scene_sampler::FlatlandScene,
    path: &PathBuf,
) -> Result<()> {
    use gcr::output::flatland::{Stroke, draw_segments};
    let pieces = 64;
    let mut points = Vec::new();
    for (si, s) in flat.segments.iter().enumerate() {
        let n = glam::DVec3::new(s.normal.x, s.normal.y, 0.0);
        for j in 0..=pieces {
            let p = s.point(j as f64 / pieces as f64);
            points.push((glam::DVec3::new(p.x, p.y, 0.0), n, si as u32));
        }
    }
    let b = radiosity_at_points(domain, trained, emitters, config, &points)?;
    let mut strokes = Vec::new();
    for (si, s) in flat.segments.iter().enumerate() {
        for j in 0..pieces {
            let (t0, t1) = (j as f64 / pieces as f64, (j + 1) as f64 / pieces as f64);
            let at = si * (pieces + 1) + j;
            strokes.push(Stroke {
                a: s.point(t0),
                b: s.point(t1),
                ba: b[at].radiosity,
                bb: b[at + 1].radiosity,
                normal: s.normal,
            });
        }
    }
    let lit: Vec<[f64; 3]> = strokes.iter().map(|s| s.ba).collect();
    let exposure = Exposure::auto(lit);
    let size = 512;
    let px = draw_segments(&strokes, flat.view.min, flat.view.max, size, 4.0, &exposure);
    image::RgbImage::from_raw(size, size, px)
        .context("image buffer")?
        .save(path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// The light flow over (s, t) ∈ [0,1]² (fig. 4.1b): two 256² panels, the sampled kernel K·s with
/// GCR's own final strength s = E + B_refl on the left and the network's Ψ on the right, on one
/// grey scale (white = 0, black = the 99th percentile of K·s; band 0), the training rays as red
/// dots on the right.
fn flatland_kernel_image(
    domain: &Domain,
    sampler: &FlatKernelSampler,
    trained: &gcr::Trained,
    path: &PathBuf,
) -> Result<()> {
    use rayon::prelude::*;
    let n = 256usize;
    let pairs: Vec<(f64, f64)> = (0..n * n)
        .into_par_iter()
        .map(|i| {
            let s = (i % n) as f64 / n as f64 + 0.5 / n as f64;
            let t = 1.0 - ((i / n) as f64 + 0.5) / n as f64;
            let ray = domain.ray(&[s, t]);
            let strength = ray.emission_x[0] + trained.reflected_kernel(ray.x, ray.nx)[0];
            (
                ray.kernel[0] * strength,
                trained.kernel.evaluate(ray.x, ray.nx, ray.y, ray.ny)[0],
            )
        })
        .collect();
    let mut sorted: Vec<f64> = pairs
        .iter()
        .map(|p| p.0)
        .filter(|v| v.is_finite())
        .collect();
    sorted.sort_by(f64::total_cmp);
    let top = sorted
        .get(sorted.len() * 99 / 100)
        .copied()
        .filter(|v| *v > 0.0)
        .unwrap_or(1.0);
    let grey = |v: f64| 255 - ((v / top).clamp(0.0, 1.0) * 255.0).round() as u8;
    let (w, gap) = (2 * n + 8, 8);
    let mut img = image::RgbImage::from_pixel(w as u32, n as u32, image::Rgb([255, 255, 255]));
    for (i, (exact, psi)) in pairs.iter().enumerate() {
        let (x, y) = ((i % n) as u32, (i / n) as u32);
        img.put_pixel(x, y, image::Rgb([grey(*exact); 3]));
        img.put_pixel((n + gap) as u32 + x, y, image::Rgb([grey(*psi); 3]));
    }
    for smp in &trained.samples {
        let s = sampler
            .sampler
            .inverse(smp.ray.face_x, smp.ray.x.truncate());
        let t = sampler
            .sampler
            .inverse(smp.ray.face_y, smp.ray.y.truncate());
        let x = (n + gap) as f64 + (s * n as f64).min(n as f64 - 1.0);
        let y = ((1.0 - t) * n as f64).min(n as f64 - 1.0);
        img.put_pixel(x as u32, y as u32, image::Rgb([220, 30, 30]));
    }
    img.save(path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// `gcr reference`: adaptive path tracing at the probes until `rel_error` (or `max_paths`).
fn reference(
    scene: &str,
    probes: &PathBuf,
    probe_out: &PathBuf,
    rel_error: f64,
    max_paths: usize,
    seed: u64,
) -> Result<()> {
    let start = Instant::now();
    let adaptive = baselines::Adaptive {
        rel_error,
        max_paths,
        seed,
        ..baselines::Adaptive::default()
    };
    let loaded = scene_sampler::load_or_builtin(scene)
        .with_context(|| format!("loading scene `{scene}`"))?;
    for w in loaded.warnings() {
        eprintln!("warning: {w}");
    }
    let source = probes.display().to_string();
    let (estimates, grey) = match loaded {
        AnyScene::ThreeD(s) => {
            let points = s.snap_probes(&scene_sampler::read_probes(probes)?, &source)?;
            let bvh = SceneBvh::new(&s);
            let est = baselines::pointwise::radiosity_adaptive(&s, &bvh, &points, &adaptive)?;
            (est, false)
        }
        AnyScene::Flatland(s) => {
            let points = s.snap_probes(&scene_sampler::read_flat_probes(probes)?, &source)?;
            let vis = scene_sampler::FlatVisibility::new(&s);
            let est = baselines::flatland::path_trace_adaptive(&s, &vis, &points, &adaptive)?;
            (est, s.bands == 1)
        }
    };
    let mut out = String::new();
    let (mut paths, mut worst) = (0usize, 0.0f64);
    for e in &estimates {
        if grey {
            out.push_str(&format!("{}\n", e.mean[0]));
        } else {
            out.push_str(&format!("{} {} {}\n", e.mean[0], e.mean[1], e.mean[2]));
        }
        paths += e.paths;
        for b in 0..3 {
            if e.mean[b] > 0.0 {
                worst = worst.max(e.std_error[b] / e.mean[b]);
            }
        }
    }
    std::fs::write(probe_out, out).with_context(|| format!("writing {}", probe_out.display()))?;
    eprintln!(
        "reference: {} probes, {paths} paths, worst relative standard error {:.4}, {:.1} s",
        estimates.len(),
        worst,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
