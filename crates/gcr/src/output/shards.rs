//! Sharded probe runs: each shard's partial probe output, and their merge into the probe output
//! a single run writes, byte for byte.
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

use crate::config::{Shard, SolveConfig};
use crate::domain::Domain;
use glam::DVec3;

/// The fingerprint of a sharded run (module docs): FNV-1a over the scene's summary, the probes
/// and the settings with the shard removed.
pub fn fingerprint(domain: &Domain, probes: &[(DVec3, DVec3, u32)], config: &SolveConfig) -> u64 {
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
    h.0
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

/// The partial probe output of `shard` (module docs): the header, then for each probe index in
/// `indices` (ascending) its line from `lines` (the single run's lines, one per probe, each
/// ending in a newline).
pub fn partial_text(shard: Shard, fingerprint: u64, lines: &[String], indices: &[usize]) -> String {
    let mut out = format!(
        "{HEADER} {shard} of {} points, fingerprint {fingerprint:016x}\n",
        lines.len()
    );
    for &i in indices {
        out.push_str(&format!("{i} {}", lines[i]));
    }
    out
}

const HEADER: &str = "# gcr probe shard";

/// A partial probe output that cannot be merged, or a set of them that does not make a run.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
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
    shard: Shard,
    points: usize,
    fingerprint: String,
    /// (probe index, its line without the index).
    lines: Vec<(usize, String)>,
}

/// Parses the partial probe output `text` of the file `name`.
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
    let (shard, points, fingerprint) = match fields[..] {
        [
            "#",
            "gcr",
            "probe",
            "shard",
            shard,
            "of",
            m,
            "points,",
            "fingerprint",
            f,
        ] => {
            let shard: Shard = (shard.parse()).map_err(|e| bad(1, format!("{e}")))?;
            let m: usize = m
                .parse()
                .map_err(|_| bad(1, format!("probe count `{m}`")))?;
            (shard, m, f.to_string())
        }
        _ => {
            return Err(bad(
                1,
                format!(
                    "not a partial probe output of `gcr solve --shard` (it starts with \
                     `{HEADER} I/N of M points, fingerprint F`)"
                ),
            ));
        }
    };
    let mut out = Vec::new();
    for (k, line) in lines.enumerate() {
        let (index, rest) = line
            .split_once(' ')
            .ok_or_else(|| bad(k + 2, "no value".into()))?;
        let index: usize =
            (index.parse()).map_err(|_| bad(k + 2, format!("probe index `{index}`")))?;
        if index >= points || !rest.ends_with('\n') {
            return Err(bad(
                k + 2,
                format!("probe {index} of {points}, or the line is cut short"),
            ));
        }
        out.push((index, rest.to_string()));
    }
    Ok(Partial {
        name: name.to_string(),
        shard,
        points,
        fingerprint,
        lines: out,
    })
}

/// Merges the partial probe outputs `parts` (file name, text) into the probe output of the
/// single run: every shard 0…N−1 once, one fingerprint and probe count, every probe once.
pub fn merge(parts: &[(String, String)]) -> Result<String, MergeError> {
    let parts: Vec<Partial> = (parts.iter())
        .map(|(name, text)| parse(name, text))
        .collect::<Result<_, _>>()?;
    let Some(first) = parts.first() else {
        return Err(MergeError::Mismatch(
            "no partial probe output to merge".into(),
        ));
    };
    let count = first.shard.count;
    let mut seen: Vec<Option<&str>> = vec![None; count];
    for p in &parts {
        if (p.shard.count, p.points, &p.fingerprint) != (count, first.points, &first.fingerprint) {
            return Err(MergeError::Mismatch(format!(
                "{} is shard {} of {} points, fingerprint {}; {} is {} of {} points, \
                 fingerprint {}: not shards of one run",
                p.name,
                p.shard,
                p.points,
                p.fingerprint,
                first.name,
                first.shard,
                first.points,
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
                    "probe {i} is in two shards (the second: {})",
                    p.name
                )));
            }
        }
    }
    if let Some(missing) = lines.iter().position(Option::is_none) {
        return Err(MergeError::Mismatch(format!(
            "probe {missing} is in no shard: a partial output is cut short or of another run"
        )));
    }
    Ok(lines.into_iter().flatten().collect())
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
                    partial_text(shard, 0xabc, &lines(), idx),
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
        assert_eq!(merge(&p).unwrap(), lines().concat());
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
        assert!(err(p).contains("x.txt:1: not a partial probe output"));
        let mut p = parts(&[(0, &[0, 1, 2]), (1, &[3, 4])], 2);
        p[1].1.pop();
        assert!(err(p).contains("p1:3: probe 4 of 5, or the line is cut short"));
        assert!(merge(&[]).unwrap_err().to_string().contains("no partial"));
    }
}
