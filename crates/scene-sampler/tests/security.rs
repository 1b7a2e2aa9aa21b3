//! Untrusted scene files (issue 35, security items 1–3): a scene reads nothing outside its own
//! folder unless allowed, reads regular files only and within a size bound, and decodes only the
//! textures it uses, within a bound on their decoded memory.
//!
//! Every test builds its hostile files in its own folder under the system's temp directory: the
//! scene in `<root>/scene/`, the files it must not reach in `<root>/secret/`.

mod common;

use common::base64;
use scene_sampler::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// A fresh `(root, scene folder)` pair, with `root/secret/` holding a valid buffer (`geo.bin`),
/// texture (`t.png`) and material library (`x.mtl`) outside the scene's folder.
fn sandbox(name: &str) -> (PathBuf, PathBuf) {
    static COUNT: AtomicUsize = AtomicUsize::new(0);
    let root = std::env::temp_dir().join(format!(
        "gcr-security-{}-{name}-{}",
        std::process::id(),
        COUNT.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&root);
    let (scene, secret) = (root.join("scene"), root.join("secret"));
    std::fs::create_dir_all(&scene).unwrap();
    std::fs::create_dir_all(&secret).unwrap();
    std::fs::write(secret.join("geo.bin"), geometry()).unwrap();
    std::fs::write(secret.join("t.png"), small_png(2, 2)).unwrap();
    std::fs::write(secret.join("x.mtl"), MTL).unwrap();
    (root, scene)
}

/// Runs `f` on another thread and gives its result, or panics if it takes longer than `secs`
/// (a loader blocked on a FIFO, or reading an endless device, never returns).
fn within<T: Send + 'static>(secs: u64, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(Duration::from_secs(secs))
        .unwrap_or_else(|_| panic!("no answer within {secs} s (blocked, or reading without bound)"))
}

/// The error message of loading `path` with `options`, within 20 s.
fn load_err_with(path: &Path, options: LoadOptions) -> String {
    let p = path.to_path_buf();
    match within(20, move || load_with(&p, &options).map(|_| ())) {
        Ok(()) => panic!("{}: loaded, expected an error", path.display()),
        Err(e) => e.to_string(),
    }
}

/// The error message of loading `path` with the default options, within 20 s.
fn load_err(path: &Path) -> String {
    load_err_with(path, LoadOptions::default())
}

/// The outside-the-folder message for `uri`, whether or not the file exists.
fn assert_outside(err: &str, uri: &str) {
    let want =
        format!("refers to a file outside the scene's folder: {uri}; pass --allow-outside-files");
    assert!(err.contains(&want), "expected `{want}` in: {err}");
    for leak in ["No such file", "os error", "not found", "cannot read"] {
        assert!(
            !err.contains(leak),
            "`{leak}` tells exists from missing: {err}"
        );
    }
}

// ⟨Fixtures: a two-triangle glTF (a textured floor, an emitting lamp above it), OBJ + MTL, PNGs⟩

/// Floor triangle (y = 0, facing up), its texture coordinates, the lamp (y = 1, facing down): 96 bytes.
fn geometry() -> Vec<u8> {
    let floats: [f32; 24] = [
        0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, // floor
        0.0, 0.0, 0.0, 1.0, 1.0, 0.0, // uv
        0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0, // lamp
    ];
    floats.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// The glTF document: buffer 0 at `buffer_uri`, the floor's baseColorTexture from `image_uri`, and
/// `extra_images` more images that no material uses.
fn gltf_doc(buffer_uri: &str, image_uri: &str, extra_images: &[&str]) -> String {
    let mut images = vec![serde_json::json!({ "uri": image_uri })];
    images.extend(extra_images.iter().map(|u| serde_json::json!({ "uri": u })));
    let textures: Vec<_> = (0..images.len())
        .map(|i| serde_json::json!({ "source": i }))
        .collect();
    serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"name": "floor", "mesh": 0}, {"name": "lamp", "mesh": 1}],
        "meshes": [
            {"name": "floor", "primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]},
            {"name": "lamp", "primitives": [{"attributes": {"POSITION": 2}, "material": 1}]}
        ],
        "materials": [
            {"name": "tex", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0],
                                                     "baseColorTexture": {"index": 0}}},
            {"name": "lamp", "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]},
             "emissiveFactor": [1.0, 1.0, 1.0]}
        ],
        "textures": textures,
        "images": images,
        "buffers": [{"uri": buffer_uri, "byteLength": 96}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 24},
            {"buffer": 0, "byteOffset": 60, "byteLength": 36}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 0.0, 1.0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0.0, 1.0, 0.0], "max": [1.0, 1.0, 1.0]}
        ]
    })
    .to_string()
}

/// Writes `dir/s.gltf` (and, unless `buffer_uri` points elsewhere, the buffer `geo.bin` and the
/// texture `t.png` beside it); returns the scene's path.
fn write_gltf(dir: &Path, buffer_uri: &str, image_uri: &str, extra_images: &[&str]) -> PathBuf {
    std::fs::write(dir.join("geo.bin"), geometry()).unwrap();
    std::fs::write(dir.join("t.png"), small_png(2, 2)).unwrap();
    let p = dir.join("s.gltf");
    std::fs::write(&p, gltf_doc(buffer_uri, image_uri, extra_images)).unwrap();
    p
}

const MTL: &str = "newmtl tex\nKd 0.8 0.8 0.8\nmap_Kd t.png\nnewmtl lamp\nKd 0 0 0\nKe 1 1 1\n";

/// Writes `dir/s.obj` using the material library `mtllib` (and `dir/s.mtl` with `mtl` as its
/// text); returns the OBJ's path.
fn write_obj(dir: &Path, mtllib: &str, mtl: &str) -> PathBuf {
    std::fs::write(dir.join("s.mtl"), mtl).unwrap();
    std::fs::write(dir.join("t.png"), small_png(2, 2)).unwrap();
    let obj = format!(
        "mtllib {mtllib}\nv 0 0 0\nv 0 0 1\nv 1 0 0\nvt 0 1\nvt 0 0\nvt 1 1\nusemtl tex\nf 1/1 2/2 3/3\n\
         v 0 1 0\nv 1 1 0\nv 0 1 1\nusemtl lamp\nf 4 5 6\n"
    );
    let p = dir.join("s.obj");
    std::fs::write(&p, obj).unwrap();
    p
}

/// A `w`×`h` RGB PNG (a gradient).
fn small_png(w: u32, h: u32) -> Vec<u8> {
    let img = image::RgbImage::from_fn(w, h, |x, y| {
        image::Rgb([(x * 40) as u8, (y * 40) as u8, 90])
    });
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// Deflate bits, least significant first.
struct Bits {
    out: Vec<u8>,
    acc: u64,
    n: u32,
}

impl Bits {
    fn put(&mut self, value: u32, count: u32) {
        self.acc |= u64::from(value) << self.n;
        self.n += count;
        while self.n >= 8 {
            self.out.push(self.acc as u8);
            self.acc >>= 8;
            self.n -= 8;
        }
    }
    /// A Huffman code (written most significant bit first).
    fn code(&mut self, code: u32, len: u32) {
        let rev = code.reverse_bits() >> (32 - len);
        self.put(rev, len);
    }
}

/// A valid PNG of `w`×`h` black pixels, 1-bit grey, a few hundred kilobytes for 20000×20000: its
/// zlib stream is one fixed-Huffman block of a zero byte and 258-byte copies of it.
fn png_bomb(w: u32, h: u32) -> Vec<u8> {
    let raw = u64::from(h) * (1 + u64::from(w).div_ceil(8));
    let mut bits = Bits {
        out: vec![0x78, 0x01],
        acc: 0,
        n: 0,
    };
    bits.put(1, 1); // final block
    bits.put(1, 2); // fixed Huffman codes
    bits.code(0x30, 8); // literal 0
    let mut left = raw - 1;
    while left >= 258 {
        bits.code(0b1100_0101, 8); // length 258 (code 285)
        bits.code(0, 5); // distance 1
        left -= 258;
    }
    for _ in 0..left {
        bits.code(0x30, 8);
    }
    bits.code(0, 7); // end of block
    bits.put(0, (8 - bits.n % 8) % 8); // to a byte boundary
    let mut zlib = bits.out;
    let adler = ((raw % 65521) << 16 | 1) as u32; // all zeros: a = 1, b = n
    zlib.extend_from_slice(&adler.to_be_bytes());
    let chunk = |kind: &[u8], data: &[u8], out: &mut Vec<u8>| {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc32(&body).to_be_bytes());
    };
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[1, 0, 0, 0, 0]); // 1 bit, grey, deflate, adaptive filter, no interlace
    chunk(b"IHDR", &ihdr, &mut png);
    chunk(b"IDAT", &zlib, &mut png);
    chunk(b"IEND", &[], &mut png);
    png
}

#[cfg(unix)]
fn mkfifo(path: &Path) {
    let ok = std::process::Command::new("mkfifo")
        .arg(path)
        .status()
        .unwrap()
        .success();
    assert!(ok, "mkfifo {}", path.display());
}

// ⟨Item 1: nothing outside the scene's folder⟩

/// glTF buffer URIs that leave the folder — `../`, absolute, `file://`, percent-encoded `..`, a
/// symlink — are refused with one message, whether or not the file exists; ones that stay inside
/// load.
#[test]
fn gltf_buffer_uris_outside_the_folder_are_refused() {
    let (root, dir) = sandbox("buffer");
    let secret = root.join("secret").canonicalize().unwrap();
    let abs = secret.join("geo.bin").display().to_string();
    #[cfg(unix)]
    std::os::unix::fs::symlink(secret.join("geo.bin"), dir.join("link.bin")).unwrap();
    let mut uris = vec![
        "../secret/geo.bin".to_string(),
        "../secret/missing.bin".to_string(),
        "sub/../../secret/geo.bin".to_string(),
        abs.clone(),
        format!("file://{abs}"),
        format!("file:{abs}"),
        "%2e%2e/secret/geo.bin".to_string(),
        "%2E%2E%2Fsecret%2Fgeo.bin".to_string(),
        "..%2fsecret%2fmissing.bin".to_string(),
    ];
    if cfg!(unix) {
        uris.push("link.bin".into());
    }
    for uri in &uris {
        let err = load_err(&write_gltf(&dir, uri, "t.png", &[]));
        assert_outside(&err, uri);
    }
    // one message for a file that exists and one that does not
    let there = load_err(&write_gltf(&dir, "../secret/geo.bin", "t.png", &[]));
    let gone = load_err(&write_gltf(&dir, "../secret/gone.bin", "t.png", &[]));
    assert_eq!(there.replace("geo.bin", "X"), gone.replace("gone.bin", "X"));
    // inside: plain, through a sub-folder and back, percent-encoded
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    for uri in ["geo.bin", "./sub/../geo.bin", "geo%2Ebin"] {
        let s = load(write_gltf(&dir, uri, "t.png", &[])).unwrap_or_else(|e| panic!("{uri}: {e}"));
        assert_eq!(s.into_3d().unwrap().textures.len(), 1, "{uri}");
    }
}

/// The same for the URI of an image that a material uses.
#[test]
fn gltf_image_uris_outside_the_folder_are_refused() {
    let (root, dir) = sandbox("image");
    let abs = root
        .join("secret/t.png")
        .canonicalize()
        .unwrap()
        .display()
        .to_string();
    #[cfg(unix)]
    std::os::unix::fs::symlink(&abs, dir.join("link.png")).unwrap();
    let mut uris = vec![
        "../secret/t.png".to_string(),
        "../secret/missing.png".to_string(),
        abs.clone(),
        format!("file://{abs}"),
        "%2e%2e/secret/t.png".to_string(),
    ];
    if cfg!(unix) {
        uris.push("link.png".into());
    }
    for uri in &uris {
        let err = load_err(&write_gltf(&dir, "geo.bin", uri, &[]));
        assert_outside(&err, uri);
    }
}

/// OBJ: `mtllib ../x.mtl`, an absolute `mtllib`, and `map_Kd ../t.png` (or absolute, or a symlink
/// out) are refused with the same message, existing or not.
#[test]
fn obj_material_libraries_and_textures_outside_the_folder_are_refused() {
    let (root, dir) = sandbox("obj");
    let secret = root.join("secret").canonicalize().unwrap();
    let abs_mtl = secret.join("x.mtl").display().to_string();
    for lib in ["../secret/x.mtl", "../secret/missing.mtl", abs_mtl.as_str()] {
        let err = load_err(&write_obj(&dir, lib, MTL));
        assert_outside(&err, lib);
    }
    let abs_png = secret.join("t.png").display().to_string();
    #[cfg(unix)]
    std::os::unix::fs::symlink(&abs_png, dir.join("link.png")).unwrap();
    let mut maps = vec!["../secret/t.png", "../secret/missing.png", abs_png.as_str()];
    if cfg!(unix) {
        maps.push("link.png");
    }
    for map in maps {
        let mtl = MTL.replace("map_Kd t.png", &format!("map_Kd {map}"));
        let err = load_err(&write_obj(&dir, "s.mtl", &mtl));
        assert_outside(&err, map);
    }
    // inside loads
    let s = load_obj(write_obj(&dir, "s.mtl", MTL)).unwrap();
    assert_eq!(s.textures.len(), 1);
}

/// The opt-out: with [`LoadOptions::allow_outside`] (`--allow-outside-files`) the same files load,
/// and the other bounds still hold (`/dev/zero` is still no regular file).
#[test]
fn allow_outside_reads_files_outside_the_folder() {
    let (root, dir) = sandbox("allow");
    let allow = LoadOptions {
        allow_outside: true,
        ..LoadOptions::default()
    };
    let abs = root.join("secret/geo.bin").display().to_string();
    for (buffer, image) in [
        ("../secret/geo.bin", "t.png"),
        (abs.as_str(), "../secret/t.png"),
        ("geo.bin", "%2e%2e/secret/t.png"),
    ] {
        let s = load_with(write_gltf(&dir, buffer, image, &[]), &allow);
        assert_eq!(
            s.unwrap().into_3d().unwrap().textures.len(),
            1,
            "{buffer} {image}"
        );
    }
    let mtl = MTL.replace("map_Kd t.png", "map_Kd ../secret/t.png");
    let s = load_with(write_obj(&dir, "../secret/x.mtl", MTL), &allow).unwrap();
    assert_eq!(s.into_3d().unwrap().textures.len(), 1);
    assert!(load_with(write_obj(&dir, "s.mtl", &mtl), &allow).is_ok());
    for uri in ["/dev/zero", "file:///dev/zero"] {
        let err = load_err_with(&write_gltf(&dir, uri, "t.png", &[]), allow);
        assert!(err.contains("/dev/zero: not a regular file"), "{err}");
    }
}

/// A percent-encoded URI that decodes to bytes that are not UTF-8 is an error saying so (the gltf
/// crate's importer panicked on it).
#[test]
fn percent_decoding_to_invalid_utf8_is_an_error() {
    let (_, dir) = sandbox("utf8");
    let err = load_err(&write_gltf(&dir, "%ff%fe.bin", "t.png", &[]));
    assert!(err.contains("%ff%fe.bin") && err.contains("UTF-8"), "{err}");
    let err = load_err(&write_gltf(&dir, "geo.bin", "%c3%28.png", &[]));
    assert!(err.contains("%c3%28.png") && err.contains("UTF-8"), "{err}");
}

/// An image entry with neither a `uri` nor a `bufferView` with a `mimeType` (the gltf crate panics
/// on it when asked for its source) is an error, not a panic.
#[test]
fn image_entries_without_a_source_are_errors() {
    let (_, dir) = sandbox("nosource");
    for image in [r#"{}"#, r#"{"bufferView": 0}"#] {
        let doc = gltf_doc("geo.bin", "t.png", &[])
            .replace(r#"[{"uri":"t.png"}]"#, &format!("[{image}]"));
        assert!(doc.contains(&format!("[{image}]")), "{doc}");
        let path = write_gltf(&dir, "geo.bin", "t.png", &[]);
        std::fs::write(&path, doc).unwrap();
        let err = load_err(&path);
        assert!(
            err.contains("image 0: neither a `uri` nor a `bufferView`"),
            "{err}"
        );
    }
}

// ⟨Item 2: regular files only, size-bounded⟩

/// A FIFO inside the folder named as a buffer, a material library, a texture or a probe file is
/// refused at once (opening one blocks until a writer comes).
#[cfg(unix)]
#[test]
fn fifos_are_refused_quickly() {
    let (_, dir) = sandbox("fifo");
    mkfifo(&dir.join("pipe"));
    let start = Instant::now();
    let err = load_err(&write_gltf(&dir, "pipe", "t.png", &[]));
    assert!(err.contains("not a regular file"), "{err}");
    let err = load_err(&write_gltf(&dir, "geo.bin", "pipe", &[]));
    assert!(err.contains("not a regular file"), "{err}");
    let err = load_err(&write_obj(&dir, "pipe", MTL));
    assert!(err.contains("not a regular file"), "{err}");
    let err = load_err(&write_obj(&dir, "s.mtl", &MTL.replace("t.png", "pipe")));
    assert!(err.contains("not a regular file"), "{err}");
    let fifo = dir.join("pipe");
    let err = within(20, move || read_probes(&fifo).unwrap_err().to_string());
    assert!(err.contains("not a regular file"), "{err}");
    // the scene file itself
    mkfifo(&dir.join("scene.gltf"));
    let err = load_err(&dir.join("scene.gltf"));
    assert!(err.contains("not a regular file"), "{err}");
    eprintln!(
        "six FIFOs refused in {:.1} ms",
        start.elapsed().as_secs_f64() * 1e3
    );
}

/// `--probes /dev/zero` (or `/dev/urandom`): refused at once, not read without end.
#[cfg(unix)]
#[test]
fn probe_files_must_be_regular_files() {
    for dev in ["/dev/zero", "/dev/urandom"] {
        let err = within(20, move || read_probes(dev).unwrap_err().to_string());
        assert!(
            err.contains(dev) && err.contains("not a regular file"),
            "{err}"
        );
        let err = within(20, move || read_flat_probes(dev).unwrap_err().to_string());
        assert!(err.contains("not a regular file"), "{err}");
    }
}

/// Files larger than the bound (2 GiB by default) are refused from their size, before reading:
/// a sparse 3 GiB buffer, texture, material library and probe file.
#[test]
fn oversized_files_are_refused_before_reading() {
    let (_, dir) = sandbox("large");
    let big = dir.join("big");
    std::fs::File::create(&big)
        .unwrap()
        .set_len(3 << 30)
        .unwrap();
    let start = Instant::now();
    for err in [
        load_err(&write_gltf(&dir, "big", "t.png", &[])),
        load_err(&write_gltf(&dir, "geo.bin", "big", &[])),
        load_err(&write_obj(&dir, "big", MTL)),
        load_err(&write_obj(&dir, "s.mtl", &MTL.replace("t.png", "big"))),
        within(20, move || read_probes(&big).unwrap_err().to_string()),
    ] {
        assert!(
            err.contains("larger than") && err.contains("2147483648"),
            "{err}"
        );
    }
    eprintln!(
        "five 3 GiB files refused in {:.1} ms",
        start.elapsed().as_secs_f64() * 1e3
    );
    // sparse, but no 3 GiB file is left behind in the temp directory
    let _ = std::fs::remove_file(dir.join("big"));
}

/// The bound on file size is an option: a 10 kB buffer under a 5 kB bound is refused, naming it.
#[test]
fn the_file_size_bound_is_an_option() {
    let (_, dir) = sandbox("bound");
    let path = write_gltf(&dir, "geo.bin", "t.png", &[]);
    let mut padded = geometry();
    padded.resize(10_000, 0);
    std::fs::write(dir.join("geo.bin"), padded).unwrap();
    let small = LoadOptions {
        max_file_bytes: 5000,
        ..LoadOptions::default()
    };
    let err = load_err_with(&path, small);
    assert!(
        err.contains("geo.bin: larger than the bound of 5000 bytes"),
        "{err}"
    );
    assert!(load(&path).is_ok());
}

// ⟨Item 3: decompression bombs⟩

/// A 20000×20000 PNG of a few hundred kilobytes (4.8 GB as linear RGB texels) is refused from its
/// header, naming the image and the bound: as an OBJ `map_Kd`, a glTF image file and a glTF data URI.
#[test]
fn a_png_bomb_is_refused_before_decoding() {
    let (_, dir) = sandbox("bomb");
    let bomb = png_bomb(20000, 20000);
    assert!(bomb.len() < 400_000, "{} bytes", bomb.len());
    std::fs::write(dir.join("bomb.png"), &bomb).unwrap();
    let data_uri = format!("data:image/png;base64,{}", base64(&bomb));
    let cases = [
        write_obj(&dir, "s.mtl", &MTL.replace("t.png", "bomb.png")),
        write_gltf(&dir, "geo.bin", "bomb.png", &[]),
        write_gltf(&dir, "geo.bin", &data_uri, &[]),
    ];
    for path in cases {
        let start = Instant::now();
        let err = load_err(&path);
        let ms = start.elapsed().as_secs_f64() * 1e3;
        assert!(
            err.contains("20000×20000") && err.contains("texture memory"),
            "{err}"
        );
        assert!(err.contains("1073741824"), "names the bound: {err}");
        assert!(
            err.contains("bomb.png") || err.contains("image 0"),
            "names the image: {err}"
        );
        eprintln!("{}: PNG bomb refused in {ms:.1} ms", path.display());
        assert!(ms < 5000.0, "{ms} ms");
    }
}

/// The bound on texture memory counts every texture of the scene: two 2×2 textures take 2 × 48
/// bytes; under a bound of 95 the second is refused, naming the 48 bytes already taken.
#[test]
fn the_texture_bound_counts_every_texture_of_the_scene() {
    let (_, dir) = sandbox("budget");
    std::fs::write(dir.join("u.png"), small_png(2, 2)).unwrap();
    let mtl = format!("{MTL}newmtl tex2\nKd 0.5 0.5 0.5\nmap_Kd u.png\n");
    let path = write_obj(&dir, "s.mtl", &mtl);
    let bound = |max_texture_bytes| LoadOptions {
        max_texture_bytes,
        ..LoadOptions::default()
    };
    let err = load_err_with(&path, bound(95));
    assert!(
        err.contains("u.png: 2×2 texels would take 48 bytes"),
        "{err}"
    );
    assert!(
        err.contains("bound of 95 bytes") && err.contains("48 bytes already taken"),
        "{err}"
    );
    assert_eq!(
        load_with(&path, &bound(96))
            .unwrap()
            .into_3d()
            .unwrap()
            .textures
            .len(),
        2
    );
    let gltf = write_gltf(&dir, "geo.bin", "t.png", &[]);
    assert!(load_err_with(&gltf, bound(47)).contains("bound of 47 bytes"));
    assert!(load_with(&gltf, &bound(48)).is_ok());
}

/// glTF images that no material's baseColorTexture uses are never read or decoded: not a file that
/// is no image, not a bomb, not a file outside the folder.
#[test]
fn unused_gltf_images_are_not_decoded() {
    let (_, dir) = sandbox("unused");
    std::fs::write(dir.join("junk.png"), b"this is no PNG").unwrap();
    std::fs::write(dir.join("bomb.png"), png_bomb(20000, 20000)).unwrap();
    let path = write_gltf(
        &dir,
        "geo.bin",
        "t.png",
        &["junk.png", "bomb.png", "../secret/t.png"],
    );
    let start = Instant::now();
    let s = load_gltf(&path).unwrap();
    assert_eq!(s.textures.len(), 1);
    eprintln!(
        "three unused images skipped: loaded in {:.1} ms",
        start.elapsed().as_secs_f64() * 1e3
    );
}

/// The fixtures are what they claim: the bomb's stream decodes (a small one, with its 258-byte
/// copies), the in-folder scenes load.
#[test]
fn fixtures_are_valid() {
    let (_, dir) = sandbox("fixtures");
    for (w, h) in [(13, 3), (5000, 40)] {
        std::fs::write(dir.join("small.png"), png_bomb(w, h)).unwrap();
        let img = image::open(dir.join("small.png")).unwrap();
        assert_eq!((img.width(), img.height()), (w, h));
        assert!(img.to_luma8().iter().all(|&v| v == 0));
    }
    assert!(load(write_gltf(&dir, "geo.bin", "t.png", &[])).is_ok());
    assert!(load(write_obj(&dir, "s.mtl", MTL)).is_ok());
}
