//! Sharded runs: each shard's partial output (probes or lightmap texels), and their merge into
//! what a single run writes, byte for byte.
//!
//! `gcr solve … --probes in.pts --probe-out part-I.txt --shard I/N` estimates only the probes
//! of shard I ([`crate::shard_points`]: whole blocks of the paths gather, so each value is the
//! single run's) and writes them as a **partial probe output** (FORMATS.md):
//!
//! ```text
//! # gcr probe shard 1/4 of 2000 points, fingerprint 0f3a9c1e22b7d405
//! 17 0.5127 0.4411 0.3012
//! 18 0.5090 0.4398 0.2996
//! ```
//!
//! one line per probe of the shard: its index in the probe file (from 0), then the line the
//! single run's probe output has for it. The fingerprint hashes the scene (its frame, measure,
//! elements and light bound), every probe (not only the shard's) and the solve's settings (the
//! shard excepted), so that shards of different runs are not merged. `gcr merge` ([`merge`])
//! checks that every shard 0…N−1 is there once, with the same fingerprint and probe count, and
//! that the indices cover every probe once, and writes the lines in probe order.
//!
//! A lightmap's texels are sharded the same way ([`Kind::Lightmap`]): `gcr solve … --lightmap
//! out.glb --shard I/N` writes `out.shard-I-of-N.txt` ([`part_path`]), whose lines hold
//! each texel's whole estimate ([`gathered_line`]), and `gcr solve … --lightmap out.glb
//! --from-shards PARTS…` lays the atlas out again, takes the texels' values from the parts
//! instead of gathering them, and writes the single run's files ([`merged_estimates`]). So are
//! a per-pixel image's pixels from a fixed camera ([`Kind::Image`]: strips of rows are its
//! blocks, `super::pixel`): `gcr solve … --image out.exr --shard I/N` writes
//! `out.shard-I-of-N.txt`, and `--image out.exr --from-shards PARTS…` the single run's image.

use crate::config::{Shard, SolveConfig};
use crate::domain::Domain;
use crate::gather::Gathered;
use glam::DVec3;
use std::path::{Path, PathBuf};

/// What a partial output holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Probe values (`--probes`, `--probe-out`), merged by `gcr merge`.
    Probes,
    /// Lightmap texels (`--lightmap`), merged by `gcr solve … --from-shards`.
    Lightmap,
    /// A per-pixel image's pixels (`--image … --image-mode pixel` from a fixed camera), merged
    /// by `gcr solve … --from-shards`.
    Image,
}

/// Every kind, for reading a header.
const KINDS: [Kind; 3] = [Kind::Probes, Kind::Lightmap, Kind::Image];

impl Kind {
    /// The header's words: what, and what its points are called (`("probe", "points")`).
    pub fn words(self) -> (&'static str, &'static str) {
        match self {
            Kind::Probes => ("probe", "points"),
            Kind::Lightmap => ("lightmap", "texels"),
            Kind::Image => ("image", "pixels"),
        }
    }
}

/// The fingerprint of a sharded run (module docs): FNV-1a over the scene's summary, the points
/// and the settings with the shard removed, and `extra` (a lightmap's settings).
pub fn fingerprint(
    domain: &Domain,
    probes: &[(DVec3, DVec3, u32)],
    config: &SolveConfig,
    extra: &str,
) -> u64 {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    let (origin, diagonal) = domain.frame();
    for v in [
        origin.x,
        origin.y,
        origin.z,
        diagonal,
        domain.total_measure(),
    ] {
        h.add(&v.to_bits().to_le_bytes());
    }
    h.add(&(domain.elements().len() as u64).to_le_bytes());
    for b in domain.radiosity_bound() {
        h.add(&b.to_bits().to_le_bytes());
    }
    for &(y, n, face) in probes {
        for v in [y.x, y.y, y.z, n.x, n.y, n.z] {
            h.add(&v.to_bits().to_le_bytes());
        }
        h.add(&face.to_le_bytes());
    }
    let mut unsharded = config.clone();
    unsharded.paths.shard = None;
    h.add(format!("{unsharded:?}").as_bytes());
    h.add(extra.as_bytes());
    h.0
}

/// Where a shard's partial lightmap or image goes: `<stem>.shard-I-of-N.txt` beside the target
/// (the lightmap's .glb, the image).
pub fn part_path(target: &Path, shard: Shard) -> PathBuf {
    let stem = target
        .file_stem()
        .map_or("output".into(), |s| s.to_string_lossy());
    target.with_file_name(format!(
        "{stem}.shard-{}-of-{}.txt",
        shard.index, shard.count
    ))
}

/// A texel's whole estimate as one line of a lightmap's partial output: B (or E), its share
/// from the networks, its standard error, its replicates' signed spread (three bands each), the
/// rays and whether guided.
/// Rust prints an f64 with the fewest digits that read back to the same bits, so the merge
/// restores every value exactly.
pub fn gathered_line(g: &Gathered) -> String {
    let b = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:?}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    format!(
        "{} {} {} {} {} {}\n",
        b(&g.radiosity),
        b(&g.from_networks),
        b(&g.std_error),
        b(&g.spread),
        g.rays,
        u8::from(g.guided)
    )
}

/// The estimate a [`gathered_line`] holds (`None` for a malformed line).
pub fn parse_gathered(line: &str) -> Option<Gathered> {
    let f: Vec<&str> = line.split_whitespace().collect();
    let bands = scene_sampler::BANDS;
    if f.len() != 4 * bands + 2 {
        return None;
    }
    let v = |k: usize| -> Option<[f64; scene_sampler::BANDS]> {
        let mut out = [0.0; scene_sampler::BANDS];
        for (b, o) in out.iter_mut().enumerate() {
            *o = f[k * bands + b].parse().ok()?;
        }
        Some(out)
    };
    Some(Gathered {
        radiosity: v(0)?,
        from_networks: v(1)?,
        std_error: v(2)?,
        spread: v(3)?,
        rays: f[4 * bands].parse().ok()?,
        guided: match f[4 * bands + 1] {
            "0" => false,
            "1" => true,
            _ => return None,
        },
    })
}

/// The estimates (one per point, in order) of `merged` shards of `kind` ([`gathered_line`]s),
/// checked to be of the run whose fingerprint is `fingerprint` (hexadecimal); the error says
/// why not.
pub fn merged_estimates(
    merged: &Merged,
    kind: Kind,
    fingerprint: &str,
) -> Result<Vec<Gathered>, String> {
    let (what, unit) = kind.words();
    if merged.kind != kind {
        return Err(format!(
            "these are shards of {} {}, not of {what} {unit}",
            merged.kind.words().0,
            merged.kind.words().1
        ));
    }
    if merged.fingerprint != fingerprint {
        return Err(format!(
            "the shards have fingerprint {}, this run {fingerprint}: they are of another scene, \
             {what} or solve settings (give the options of the shard runs, --shard excepted, \
             --block-points included)",
            merged.fingerprint
        ));
    }
    (merged.text.lines().enumerate())
        .map(|(i, line)| {
            parse_gathered(line).ok_or_else(|| format!("{what} {i}: not an estimate: `{line}`"))
        })
        .collect()
}

/// FNV-1a, 64 bits.
struct Fnv(u64);

impl Fnv {
    fn add(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// The partial output of `shard` (module docs): the header, then for each point index in
/// `indices` (ascending) its line from `lines` (the single run's lines, one per point, each
/// ending in a newline).
pub fn partial_text(
    kind: Kind,
    shard: Shard,
    fingerprint: u64,
    lines: &[String],
    indices: &[usize],
) -> String {
    let (what, unit) = kind.words();
    let mut out = format!(
        "# gcr {what} shard {shard} of {} {unit}, fingerprint {fingerprint:016x}\n",
        lines.len()
    );
    for &i in indices {
        out.push_str(&format!("{i} {}", lines[i]));
    }
    out
}

/// A partial probe output that cannot be merged, or a set of them that does not make a run.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// A part that cannot be read, or is not text.
    #[error("{name}: {what}")]
    Read {
        /// The file's name.
        name: String,
        /// Why.
        what: String,
    },
    /// Not a partial probe output, or a malformed line.
    #[error("{name}:{line}: {what}")]
    Malformed {
        /// The file's name.
        name: String,
        /// The line (from 1).
        line: usize,
        /// What is wrong.
        what: String,
    },
    /// Partial outputs of different runs, or a wrong set of shards.
    #[error("{0}")]
    Mismatch(String),
}

/// One parsed partial output.
struct Partial {
    name: String,
    kind: Kind,
    shard: Shard,
    points: usize,
    fingerprint: String,
    /// (probe index, its line without the index).
    lines: Vec<(usize, String)>,
}

/// Parses the partial output `text` of the file `name`.
fn parse(name: &str, text: &str) -> Result<Partial, MergeError> {
    let bad = |line: usize, what: String| MergeError::Malformed {
        name: name.to_string(),
        line,
        what,
    };
    let mut lines = text.split_inclusive('\n');
    let header = lines.next().unwrap_or("");
    let fields: Vec<&str> = header.split_whitespace().collect();
    // # gcr probe shard I/N of M points, fingerprint F
    let header = match fields[..] {
        [
            "#",
            "gcr",
            what,
            "shard",
            shard,
            "of",
            m,
            unit,
            "fingerprint",
            f,
        ] => (KINDS.iter())
            .find(|k| k.words() == (what, unit.trim_end_matches(',')))
            .map(|&kind| (kind, shard, m, f)),
        _ => None,
    };
    let Some((kind, shard, m, f)) = header else {
        return Err(bad(
            1,
            "not a partial output of `gcr solve --shard` (it starts with `# gcr probe shard I/N \
             of M points, fingerprint F`, `# gcr lightmap shard I/N of M texels, …` or `# gcr \
             image shard I/N of M pixels, …`)"
                .into(),
        ));
    };
    let what = kind.words().0;
    let shard: Shard = (shard.parse()).map_err(|e| bad(1, format!("{e}")))?;
    let points: usize = (m.parse()).map_err(|_| bad(1, format!("{what} count `{m}`")))?;
    let fingerprint = f.to_string();
    let mut out = Vec::new();
    for (k, line) in lines.enumerate() {
        let (index, rest) = line
            .split_once(' ')
            .ok_or_else(|| bad(k + 2, "no value".into()))?;
        let index: usize =
            (index.parse()).map_err(|_| bad(k + 2, format!("{what} index `{index}`")))?;
        if index >= points || !rest.ends_with('\n') {
            return Err(bad(
                k + 2,
                format!("{what} {index} of {points}, or the line is cut short"),
            ));
        }
        out.push((index, rest.to_string()));
    }
    Ok(Partial {
        name: name.to_string(),
        kind,
        shard,
        points,
        fingerprint,
        lines: out,
    })
}

/// The partial outputs at `paths` as (name, text), read as scene files are (regular files, at
/// most the loader's size limit).
pub fn read_parts(paths: &[PathBuf]) -> Result<Vec<(String, String)>, MergeError> {
    let limit = scene_sampler::LoadOptions::default().max_file_bytes;
    (paths.iter())
        .map(|p| {
            let name = p.display().to_string();
            let what = |what: String| MergeError::Read {
                name: name.clone(),
                what,
            };
            let bytes = scene_sampler::confine::read_regular_file(p, limit)
                .map_err(|e| what(e.to_string()))?;
            let text = String::from_utf8(bytes)
                .map_err(|_| what("not text (a partial output is UTF-8)".into()))?;
            Ok((name, text))
        })
        .collect()
}

/// Shards merged: what they hold, the run's fingerprint and the single run's lines.
#[derive(Clone, Debug)]
pub struct Merged {
    /// Probes, lightmap texels or pixels.
    pub kind: Kind,
    /// The fingerprint every shard carries (hexadecimal, as in the headers).
    pub fingerprint: String,
    /// The lines in point order, each ending in a newline.
    pub text: String,
}

/// Merges the partial outputs `parts` (file name, text) into the lines of the single run:
/// every shard 0…N−1 once, one kind, fingerprint and point count, every point once.
pub fn merge(parts: &[(String, String)]) -> Result<Merged, MergeError> {
    let parts: Vec<Partial> = (parts.iter())
        .map(|(name, text)| parse(name, text))
        .collect::<Result<_, _>>()?;
    let Some(first) = parts.first() else {
        return Err(MergeError::Mismatch("no partial output to merge".into()));
    };
    let (count, what) = (first.shard.count, first.kind.words().0);
    let mut seen: Vec<Option<&str>> = vec![None; count];
    for p in &parts {
        let this = (p.kind, p.shard.count, p.points, &p.fingerprint);
        if this != (first.kind, count, first.points, &first.fingerprint) {
            return Err(MergeError::Mismatch(format!(
                "{} is {} shard {} of {} {}, fingerprint {}; {} is {} shard {} of {} {}, \
                 fingerprint {}: not shards of one run",
                p.name,
                p.kind.words().0,
                p.shard,
                p.points,
                p.kind.words().1,
                p.fingerprint,
                first.name,
                what,
                first.shard,
                first.points,
                first.kind.words().1,
                first.fingerprint
            )));
        }
        if let Some(other) = seen[p.shard.index].replace(&p.name) {
            return Err(MergeError::Mismatch(format!(
                "shard {} twice: {other} and {}",
                p.shard, p.name
            )));
        }
    }
    if let Some(missing) = seen.iter().position(Option::is_none) {
        return Err(MergeError::Mismatch(format!(
            "shard {missing}/{count} is missing ({} of {count} given)",
            parts.len()
        )));
    }
    let mut lines: Vec<Option<&str>> = vec![None; first.points];
    for p in &parts {
        for (i, line) in &p.lines {
            if lines[*i].replace(line).is_some() {
                return Err(MergeError::Mismatch(format!(
                    "{what} {i} is in two shards (the second: {})",
                    p.name
                )));
            }
        }
    }
    if let Some(missing) = lines.iter().position(Option::is_none) {
        return Err(MergeError::Mismatch(format!(
            "{what} {missing} is in no shard: a partial output is cut short or of another run"
        )));
    }
    Ok(Merged {
        kind: first.kind,
        fingerprint: first.fingerprint.clone(),
        text: lines.into_iter().flatten().collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines() -> Vec<String> {
        (0..5).map(|i| format!("{i}.5 0.25 1e-3\n")).collect()
    }

    fn parts(shards: &[(usize, &[usize])], count: usize) -> Vec<(String, String)> {
        (shards.iter())
            .map(|&(index, idx)| {
                let shard = Shard { index, count };
                (
                    format!("p{index}"),
                    partial_text(Kind::Probes, shard, 0xabc, &lines(), idx),
                )
            })
            .collect()
    }

    #[test]
    fn shards_merge_into_the_single_runs_lines() {
        let p = parts(&[(1, &[1, 4]), (0, &[0, 2, 3])], 2);
        assert!(
            p[1].1.starts_with(
                "# gcr probe shard 0/2 of 5 points, fingerprint 0000000000000abc\n0 0.5"
            )
        );
        let merged = merge(&p).unwrap();
        assert_eq!(merged.text, lines().concat());
        assert_eq!(
            (merged.kind, merged.fingerprint.as_str()),
            (Kind::Probes, "0000000000000abc")
        );
    }

    #[test]
    fn wrong_sets_of_shards_are_refused() {
        let err = |p: Vec<(String, String)>| merge(&p).unwrap_err().to_string();
        assert!(err(parts(&[(0, &[0, 1, 2])], 2)).contains("shard 1/2 is missing"));
        assert!(err(parts(&[(0, &[0, 1, 2]), (0, &[3, 4])], 2)).contains("shard 0/2 twice"));
        assert!(err(parts(&[(0, &[0, 1, 2]), (1, &[2, 3, 4])], 2)).contains("probe 2 is in two"));
        assert!(err(parts(&[(0, &[0, 1]), (1, &[3, 4])], 2)).contains("probe 2 is in no shard"));
        let mut p = parts(&[(0, &[0, 1, 2]), (1, &[3, 4])], 2);
        p[1].1 = p[1].1.replace("0000000000000abc", "0000000000000abd");
        assert!(err(p).contains("not shards of one run"));
        let p = vec![("x.txt".to_string(), "0.5 0.5 0.5\n".to_string())];
        assert!(err(p).contains("x.txt:1: not a partial output"));
        let mut p = parts(&[(0, &[0, 1, 2]), (1, &[3, 4])], 2);
        p[1].1.pop();
        assert!(err(p).contains("p1:3: probe 4 of 5, or the line is cut short"));
        assert!(merge(&[]).unwrap_err().to_string().contains("no partial"));
        // a lightmap part among probe parts
        let mut p = parts(&[(0, &[0, 1, 2]), (1, &[3, 4])], 2);
        p[1].1 = p[1].1.replacen(
            "probe shard 1/2 of 5 points",
            "lightmap shard 1/2 of 5 texels",
            1,
        );
        assert!(err(p).contains("p1 is lightmap shard 1/2 of 5 texels"));
    }

    #[test]
    fn gathered_lines_restore_every_bit() {
        let g = Gathered {
            radiosity: [0.1 + 0.2, 1e-310, 123456.789],
            from_networks: [0.0, -0.0, 1.0 / 3.0],
            std_error: [f64::MIN_POSITIVE, 2.5e-17, 7.0],
            spread: [-f64::MIN_POSITIVE, 2.5e-17, -7.0],
            rays: 65536,
            guided: true,
        };
        let line = gathered_line(&g);
        assert!(line.ends_with('\n'));
        let back = parse_gathered(&line).unwrap();
        let bits = |g: &Gathered| {
            let v = [g.radiosity, g.from_networks, g.std_error, g.spread].concat();
            (
                v.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                g.rays,
                g.guided,
            )
        };
        assert_eq!(bits(&back), bits(&g));
        assert!(parse_gathered("1 2 3\n").is_none());
        assert!(parse_gathered(&line.replace(" 1\n", " 2\n")).is_none());
    }
}
