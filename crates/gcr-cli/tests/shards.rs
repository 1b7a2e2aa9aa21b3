//! Issue 34, sharded runs: `gcr solve --shard I/N` writes its probes' lines with their indices,
//! and `gcr merge` joins the shards into exactly the bytes of the single run (radiosity and
//! irradiance, with blocks small enough that every shard holds several); a lightmap's texels
//! likewise, merged by `gcr solve --from-shards` into the single run's .glb and EXR pages, and a
//! per-pixel image's pixels into the single run's EXR and PNG; what
//! cannot be a shard is refused before the solve, and what cannot be merged is refused naming
//! the file.

mod common;

use common::*;

use std::path::{Path, PathBuf};
use std::process::Output;

fn ok(o: &Output) -> String {
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "failed: {err}");
    err
}

fn fails(o: &Output, needle: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains(needle), "`{needle}` not in: {err}");
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `n` probes on the Cornell box's faces, in `d/in.pts`.
fn probes(d: &Path, n: usize) -> PathBuf {
    let p = d.join("in.pts");
    cornell_probes(&p, n);
    p
}

/// Solves shards 0…count−1 (in reverse order) and merges them; the single run beside them; both
/// texts. `extra`: more options for every run.
fn sharded_and_single(d: &Path, probes: &Path, count: usize, extra: &[&str]) -> (String, String) {
    let run = |out: &Path, shard: Option<String>| {
        let mut args = vec![
            "solve",
            "cornell-box",
            "--probes",
            s(probes),
            "--probe-out",
            s(out),
        ];
        args.extend(extra);
        let shard = shard.unwrap_or_default();
        if !shard.is_empty() {
            args.extend(["--shard", &shard]);
        }
        ok(&gcr(&args));
    };
    let mut parts = Vec::new();
    for i in (0..count).rev() {
        let part = d.join(format!("part{i}.txt"));
        run(&part, Some(format!("{i}/{count}")));
        let text = std::fs::read_to_string(&part).unwrap();
        assert!(
            text.starts_with(&format!("# gcr probe shard {i}/{count} of ")),
            "{text}"
        );
        parts.push(part);
    }
    let merged = d.join("merged.txt");
    let mut args = vec!["merge", "--probe-out", s(&merged)];
    args.extend(parts.iter().map(|p| s(p)));
    let err = ok(&gcr(&args));
    assert!(err.contains(&format!("merged {count} shards")), "{err}");
    let single = d.join("single.txt");
    run(&single, None);
    (
        std::fs::read_to_string(merged).unwrap(),
        std::fs::read_to_string(single).unwrap(),
    )
}

#[test]
fn merged_shards_are_the_single_runs_bytes() {
    let d = dir("shards", "same");
    let p = probes(&d, 600);
    let blocks = ["--block-points", "64", "--quality", "draft"];
    let (merged, single) = sharded_and_single(&d, &p, 3, &blocks);
    assert_eq!(merged.lines().count(), 600);
    assert!(
        merged == single,
        "the merged shards differ from the single run"
    );
    // irradiance probes group differently (every point a white receiver): the same holds
    let mut extra = blocks.to_vec();
    extra.extend(["--probe-quantity", "irradiance"]);
    let (merged, single) = sharded_and_single(&d, &p, 4, &extra);
    assert!(merged == single, "irradiance: the merged shards differ");
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn what_cannot_be_a_shard_is_refused_before_the_solve() {
    let d = dir("shards", "refused");
    let p = probes(&d, 40);
    let out = d.join("o.txt");
    let base = [
        "solve",
        "cornell-box",
        "--probes",
        s(&p),
        "--probe-out",
        s(&out),
    ];
    let with = |more: &[&str]| {
        let mut a = base.to_vec();
        a.extend(more);
        gcr(&a)
    };
    fails(
        &with(&["--shard", "3/4", "--block-points", "64"]),
        "the 40 points make only 1 block(s) of at least 64 points, fewer than the shards",
    );
    fails(
        &with(&["--shard", "1/2"]),
        "the 40 points make only 1 block(s) (no --block-points: one block), fewer than the shards",
    );
    let img = d.join("i.png");
    fails(
        &with(&["--shard", "0/2", "--image", s(&img)]),
        "--shard splits the probes (--probes, --probe-out), a lightmap's texels (--lightmap) and \
         the pixels of one per-pixel image from a fixed camera",
    );
    let pixel = [
        "--shard",
        "0/2",
        "--image",
        s(&img),
        "--image-mode",
        "pixel",
    ];
    fails(
        &with(&[&pixel[..], &["--auto-camera"]].concat()),
        "needs the whole solution; run it without --shard",
    );
    fails(
        &with(&[&pixel[..], &["--gather", "rays"]].concat()),
        "an image by a gather other than the default",
    );
    fails(
        &with(&[&pixel[..], &["--view", "0,0.3,-1;0.3,0.3,0=v.png"]].concat()),
        "a --view image",
    );
    let o = gcr(&["solve", "cornell-box", "--shard", "0/2"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    for bad in ["2/2", "1", "a/b", "1/0"] {
        let o = with(&["--shard", bad]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{bad}: {err}");
        assert!(err.contains("expected INDEX/COUNT"), "{bad}: {err}");
    }
    assert!(
        std::fs::read_dir(&d).unwrap().count() == 1,
        "a file was written"
    );
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn shards_of_different_runs_are_not_merged() {
    let d = dir("shards", "mismatch");
    let p = probes(&d, 200);
    let part = |i: usize, seed: &str| {
        let out = d.join(format!("p{i}-{seed}.txt"));
        let shard = format!("{i}/2");
        ok(&gcr(&[
            "solve",
            "cornell-box",
            "--probes",
            s(&p),
            "--probe-out",
            s(&out),
            "--shard",
            &shard,
            "--block-points",
            "32",
            "--quality",
            "draft",
            "--seed",
            seed,
        ]));
        out
    };
    let (a, b) = (part(0, "1"), part(1, "2"));
    let merged = d.join("m.txt");
    fails(
        &gcr(&["merge", s(&a), s(&b), "--probe-out", s(&merged)]),
        "not shards of one run",
    );
    fails(
        &gcr(&["merge", s(&a), "--probe-out", s(&merged)]),
        "shard 1/2 is missing",
    );
    fails(
        &gcr(&["merge", s(&p), "--probe-out", s(&merged)]),
        "not a partial output",
    );
    assert!(!merged.exists());
    let _ = std::fs::remove_dir_all(d);
}

/// A lightmap baked in three shards and merged by `--from-shards` is the single run's .glb and
/// EXR page, byte for byte (irradiance, and radiosity denoised: every run gathers the same
/// guide, each block stops on its denoised error); shards of other settings, a missing shard and
/// `gcr merge` on lightmap shards are refused, writing nothing.
#[test]
fn lightmap_shards_merge_into_the_single_bake() {
    let d = dir("shards", "lightmap");
    for (quantity, denoise) in [("irradiance", false), ("radiosity", true)] {
        let bake_at = |density: &str, out: &Path, more: &[&str]| {
            let mut args = vec![
                "solve",
                "cornell-box",
                "--lightmap",
                s(out),
                "--lightmap-density",
                density,
                "--lightmap-quantity",
                quantity,
                "--block-points",
                "128",
                "--quality",
                "draft",
            ];
            if denoise {
                args.push("--lightmap-denoise");
            }
            args.extend(more);
            gcr(&args)
        };
        let bake = |out: &Path, more: &[&str]| bake_at("30", out, more);
        let (single, parts, merged) = (d.join("single"), d.join("parts"), d.join("merged"));
        for x in [&single, &parts, &merged] {
            let _ = std::fs::remove_dir_all(x);
            std::fs::create_dir_all(x).unwrap();
        }
        ok(&bake(&single.join("room.glb"), &[]));
        for i in [2, 0, 1] {
            ok(&bake(
                &parts.join("room.glb"),
                &["--shard", &format!("{i}/3")],
            ));
        }
        assert_eq!(
            entries(&parts),
            [
                "room.shard-0-of-3.txt",
                "room.shard-1-of-3.txt",
                "room.shard-2-of-3.txt"
            ],
            "a shard writes its part and nothing else"
        );
        let part = |i: usize| parts.join(format!("room.shard-{i}-of-3.txt"));
        let (p0, p1, p2) = (part(0), part(1), part(2));
        let glb = merged.join("room.glb");
        ok(&bake(&glb, &["--from-shards", s(&p1), s(&p2), s(&p0)]));
        assert_eq!(entries(&merged), entries(&single));
        for name in entries(&single) {
            let (a, b) = (single.join(&name), merged.join(&name));
            assert!(
                std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
                "{quantity}: {name} differs from the single run's"
            );
        }
        // refused: other settings, a shard missing, probes' merge; nothing written
        let other = merged.join("other.glb");
        let all = ["--from-shards", s(&p0), s(&p1), s(&p2)];
        fails(&bake_at("31", &other, &all), "the shards have fingerprint");
        fails(
            &bake(&other, &["--from-shards", s(&p0), s(&p2)]),
            "shard 1/3 is missing",
        );
        let probe_out = merged.join("p.txt");
        fails(
            &gcr(&[
                "merge",
                s(&p0),
                s(&p1),
                s(&p2),
                "--probe-out",
                s(&probe_out),
            ]),
            "these are a lightmap's shards",
        );
        assert!(!other.exists() && !probe_out.exists());
    }
    let _ = std::fs::remove_dir_all(d);
}

/// A per-pixel image from the scene's camera rendered in three shards of rows and merged by
/// `--from-shards` is the single run's EXR (and PNG, its exposure from the merged pixels), byte
/// for byte; other settings, a missing shard and `gcr merge` on image shards are refused.
#[test]
fn image_shards_merge_into_the_single_image() {
    let d = dir("shards", "image");
    let render = |out: &Path, more: &[&str]| {
        let mut args = vec![
            "solve",
            "cornell-box",
            "--image",
            s(out),
            "--image-mode",
            "pixel",
            "--resolution",
            "24x20",
            "--block-points",
            "48",
            "--quality",
            "draft",
        ];
        args.extend(more);
        gcr(&args)
    };
    for ext in ["exr", "png"] {
        let single = d.join(format!("single.{ext}"));
        ok(&render(&single, &[]));
        let img = d.join(format!("img.{ext}"));
        for i in [1, 2, 0] {
            ok(&render(&img, &["--shard", &format!("{i}/3")]));
        }
        assert!(!img.exists(), "a shard writes its part, not the image");
        let part = |i: usize| d.join(format!("img.shard-{i}-of-3.txt"));
        let (p0, p1, p2) = (part(0), part(1), part(2));
        let head = std::fs::read_to_string(&p1).unwrap();
        assert!(
            head.starts_with("# gcr image shard 1/3 of 480 pixels, fingerprint "),
            "{head}"
        );
        // strips of 48 pixels: 2 rows each, every third from the shard's on
        let first: usize = head
            .lines()
            .nth(1)
            .unwrap()
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert_eq!(first, 48);
        let all = ["--from-shards", s(&p2), s(&p0), s(&p1)];
        ok(&render(&img, &all));
        assert!(
            std::fs::read(&img).unwrap() == std::fs::read(&single).unwrap(),
            "{ext}: the merged image differs from the single run's"
        );
        let other = d.join(format!("other.{ext}"));
        let mut wider = all.to_vec();
        wider.extend(["--fov", "50"]);
        fails(&render(&other, &wider), "the shards have fingerprint");
        fails(
            &render(&other, &["--from-shards", s(&p0), s(&p1)]),
            "shard 2/3 is missing",
        );
        assert!(!other.exists());
    }
    let probe_out = d.join("p.txt");
    let part = |i: usize| d.join(format!("img.shard-{i}-of-3.txt"));
    fails(
        &gcr(&[
            "merge",
            s(&part(0)),
            s(&part(1)),
            s(&part(2)),
            "--probe-out",
            s(&probe_out),
        ]),
        "these are an image's shards",
    );
    let _ = std::fs::remove_dir_all(d);
}
