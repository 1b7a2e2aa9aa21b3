//! Fuzz-style robustness of every loader (issue 17): thousands of seeded random mutations of the files in
//! `scenes/` — byte flips, bytes replaced by syntax characters, truncations, duplicated, dropped and
//! inserted lines, numbers replaced by extreme values — through the OBJ (and its MTL), glTF, .glb,
//! Flatland JSON and probe loaders. Each input must give `Ok` or an error, never a panic (caught per input
//! and reported with how to rebuild it). Deterministic (ChaCha8, fixed seed); the count is bounded so the
//! whole test takes a few seconds in the test profile.
//!
//! A loader's own guard turns a panic inside tobj or gltf into a parse error; those are counted and printed
//! separately so that a third-party panic that we guard (rather than avoid) stays visible.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scene_sampler::*;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

/// Mutated inputs per base file.
const PER_FILE: usize = 250;

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

const SYNTAX: &[u8] = b"0123456789 \n\t-.e/\"{}[],:#\0\xff";
const NUMBERS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "-1",
    "1e308",
    "-1e308",
    "0",
    "1e-320",
    "4294967296",
    "-0",
    "",
    "1.",
];
const LINES: &[&str] = &[
    "f 1 2",
    "f -1 -2 -3",
    "f 0 0 0",
    "f 1/1/1 2/2/2 3/3/3",
    "f 99999 1 2",
    "usemtl",
    "usemtl nowhere",
    "mtllib",
    "mtllib /",
    "newmtl",
    "Kd",
    "Kd 0.5",
    "Ke 1 2",
    "Kd x y z",
    "o",
    "g",
    "v 1e40 0 0",
    "v 1 2",
    "v 1 2 3 0",
    "vn",
    "vn 0 0 0",
    "l 1 2",
    "s 1",
    "\u{feff}",
    "",
];

/// Which mutation, for the failure report.
#[derive(Debug, Clone, Copy)]
enum Op {
    Flip(usize, u8),
    Replace(usize, u8),
    Truncate(usize),
    DuplicateLine(usize),
    DropLine(usize),
    Number(usize, &'static str),
    InsertLine(usize, &'static str),
}

fn lines(b: &[u8]) -> Vec<&[u8]> {
    b.split(|&c| c == b'\n').collect()
}

fn join(ls: &[&[u8]]) -> Vec<u8> {
    ls.join(&b'\n')
}

fn mutate(base: &[u8], rng: &mut ChaCha8Rng, ops: &mut Vec<Op>) -> Vec<u8> {
    let mut b = base.to_vec();
    for _ in 0..rng.random_range(1..=3) {
        if b.is_empty() {
            break;
        }
        let op = match rng.random_range(0..7) {
            0 => Op::Flip(rng.random_range(0..b.len()), 1 << rng.random_range(0..8)),
            1 => Op::Replace(
                rng.random_range(0..b.len()),
                SYNTAX[rng.random_range(0..SYNTAX.len())],
            ),
            2 => Op::Truncate(rng.random_range(0..b.len())),
            3 => Op::DuplicateLine(rng.random_range(0..lines(&b).len())),
            4 => Op::DropLine(rng.random_range(0..lines(&b).len())),
            5 => Op::Number(
                rng.random_range(0..b.len()),
                NUMBERS[rng.random_range(0..NUMBERS.len())],
            ),
            _ => Op::InsertLine(
                rng.random_range(0..=lines(&b).len()),
                LINES[rng.random_range(0..LINES.len())],
            ),
        };
        ops.push(op);
        b = apply(&b, op);
    }
    b
}

fn apply(b: &[u8], op: Op) -> Vec<u8> {
    let mut b = b.to_vec();
    match op {
        Op::Flip(i, m) => b[i] ^= m,
        Op::Replace(i, c) => b[i] = c,
        Op::Truncate(n) => b.truncate(n),
        Op::DuplicateLine(k) => {
            let mut ls = lines(&b);
            ls.insert(k, ls[k]);
            b = join(&ls);
        }
        Op::DropLine(k) => {
            let mut ls = lines(&b);
            ls.remove(k);
            b = join(&ls);
        }
        Op::Number(at, with) => {
            // the number token at or after `at`, replaced
            let is_num = |c: u8| c.is_ascii_digit() || c == b'.' || c == b'-' || c == b'e';
            if let Some(s) = (at..b.len()).find(|&i| b[i].is_ascii_digit()) {
                let s = (0..=s)
                    .rev()
                    .take_while(|&i| is_num(b[i]))
                    .last()
                    .unwrap_or(s);
                let e = (s..b.len()).find(|&i| !is_num(b[i])).unwrap_or(b.len());
                b.splice(s..e, with.bytes());
            }
        }
        Op::InsertLine(k, l) => {
            let mut ls = lines(&b);
            ls.insert(k, l.as_bytes());
            b = join(&ls);
        }
    }
    b
}

fn base64_decode(s: &str) -> Vec<u8> {
    let val = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        _ => 63,
    };
    let b: Vec<u8> = s.bytes().filter(|&c| c != b'=').collect();
    let mut out = Vec::new();
    for c in b.chunks(4) {
        let n = c
            .iter()
            .enumerate()
            .fold(0u32, |n, (k, &x)| n | u32::from(val(x)) << (18 - 6 * k));
        out.extend_from_slice(&n.to_be_bytes()[1..c.len()]);
    }
    out
}

/// A binary glTF (.glb: JSON chunk + BIN chunk) of a `.gltf` whose single buffer is a base64 data URI.
fn to_glb(gltf_text: &str) -> Vec<u8> {
    let mut doc: serde_json::Value = serde_json::from_str(gltf_text).unwrap();
    let uri = doc["buffers"][0]["uri"].as_str().unwrap().to_string();
    let bin = base64_decode(uri.split_once(',').unwrap().1);
    doc["buffers"][0] = serde_json::json!({ "byteLength": bin.len() });
    let mut json = serde_json::to_vec(&doc).unwrap();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut bin = bin;
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// One base file and how to run its mutations.
struct Case {
    /// The file name written (its extension picks the loader).
    name: String,
    /// Unmutated content.
    bytes: Vec<u8>,
    /// Files written beside it unmutated (an OBJ's MTL, or the OBJ of a mutated MTL).
    beside: Vec<(String, Vec<u8>)>,
    /// What to run on the written path: the scene loader's error message, if it is one that failed.
    run: fn(&Path, &str) -> Option<String>,
}

fn load_scene(p: &Path, _: &str) -> Option<String> {
    match load(p) {
        // a scene that loads must be usable: bounds, BVH and one query
        Ok(AnyScene::ThreeD(s)) => {
            assert!(s.faces.iter().all(|f| f.area > 0.0 && f.normal.is_finite()));
            let bvh = SceneBvh::with_quality(&s, BuildQuality::Medium);
            let c = s.faces[0].centroid();
            let _ = bvh.closest_hit(
                c + s.faces[0].normal,
                -s.faces[0].normal,
                f64::INFINITY,
                u32::MAX,
            );
            None
        }
        Ok(AnyScene::Flatland(s)) => {
            let _ = FlatVisibility::new(&s);
            None
        }
        Err(e) => Some(e.to_string()),
    }
}

fn load_3d_probes(p: &Path, scene: &str) -> Option<String> {
    if let Ok(probes) = read_probes(p) {
        let s = builtin(scene).unwrap().into_3d().unwrap();
        let _ = s.snap_probes(&probes, "fuzz");
    }
    Some(String::new())
}

fn load_flat_probes(p: &Path, scene: &str) -> Option<String> {
    if let Ok(probes) = read_flat_probes(p) {
        let s = builtin(scene).unwrap().into_flatland().unwrap();
        let _ = s.snap_probes(&probes, "fuzz");
    }
    Some(String::new())
}

fn cases() -> Vec<Case> {
    let dir = scenes_dir();
    let read = |n: &str| std::fs::read(dir.join(n)).unwrap();
    let mut out = Vec::new();
    for name in ["cornell-box", "wall-floor", "two-blockers", "furnace"] {
        let (obj, mtl) = (read(&format!("{name}.obj")), read(&format!("{name}.mtl")));
        out.push(Case {
            name: format!("{name}.obj"),
            bytes: obj.clone(),
            beside: vec![(format!("{name}.mtl"), mtl.clone())],
            run: load_scene,
        });
        out.push(Case {
            name: format!("{name}.mtl"),
            bytes: mtl,
            beside: vec![(format!("{name}.obj"), obj)],
            run: |p, _| load_scene(&p.with_extension("obj"), ""),
        });
        let gltf = read(&format!("{name}.gltf"));
        out.push(Case {
            name: format!("{name}.glb"),
            bytes: to_glb(std::str::from_utf8(&gltf).unwrap()),
            beside: vec![],
            run: load_scene,
        });
        out.push(Case {
            name: format!("{name}.gltf"),
            bytes: gltf,
            beside: vec![],
            run: load_scene,
        });
        out.push(Case {
            name: format!("{name}.probes.txt"),
            bytes: read(&format!("{name}.probes.txt")),
            beside: vec![],
            run: load_3d_probes,
        });
    }
    for name in ["flatland-corner", "flatland-blocker"] {
        out.push(Case {
            name: format!("{name}.json"),
            bytes: read(&format!("{name}.json")),
            beside: vec![],
            run: load_scene,
        });
        out.push(Case {
            name: format!("{name}.probes.txt"),
            bytes: read(&format!("{name}.probes.txt")),
            beside: vec![],
            run: load_flat_probes,
        });
    }
    out
}

#[test]
fn mutated_files_never_panic_a_loader() {
    let root = std::env::temp_dir().join(format!("scene-sampler-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&root).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(0x17);
    let mut panics = Vec::new();
    let mut guarded = Vec::new();
    let (mut total, mut loaded) = (0usize, 0usize);
    for case in cases() {
        // the unmutated files load (so mutations start from valid input)
        let dir = root.join(&case.name);
        std::fs::create_dir_all(&dir).unwrap();
        for (n, b) in &case.beside {
            std::fs::write(dir.join(n), b).unwrap();
        }
        let path = dir.join(&case.name);
        std::fs::write(&path, &case.bytes).unwrap();
        let scene = case.name.split('.').next().unwrap().to_string();
        assert_eq!(
            (case.run)(&path, &scene).filter(|e| !e.is_empty()),
            None,
            "{}",
            case.name
        );
        for k in 0..PER_FILE {
            let mut ops = Vec::new();
            let bytes = mutate(&case.bytes, &mut rng, &mut ops);
            std::fs::write(&path, &bytes).unwrap();
            total += 1;
            match catch_unwind(AssertUnwindSafe(|| (case.run)(&path, &scene))) {
                Ok(None) => loaded += 1,
                // loaders that guard a third-party panic say so in their error
                Ok(Some(e)) if e.contains("parser") && e.contains("failed") => {
                    guarded.push(format!("{} #{k} {ops:?}: {e}", case.name));
                }
                Ok(Some(_)) => {}
                Err(e) => {
                    let msg = e
                        .downcast_ref::<String>()
                        .cloned()
                        .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
                        .unwrap_or_default();
                    panics.push(format!("{} #{k} {ops:?}: {msg}", case.name));
                }
            }
        }
        // leave the valid file for the next case's reference
        std::fs::write(&path, &case.bytes).unwrap();
    }
    let _ = std::fs::remove_dir_all(&root);
    eprintln!(
        "fuzz: {total} mutated inputs, {loaded} scenes still loaded, {} third-party panics guarded",
        guarded.len()
    );
    for g in &guarded {
        eprintln!("guarded: {g}");
    }
    assert!(
        panics.is_empty(),
        "{} panics:\n{}",
        panics.len(),
        panics.join("\n")
    );
    // the mutations are not all fatal: the test exercises the paths past the parsers too
    assert!(loaded > total / 20, "{loaded} of {total}");
}
