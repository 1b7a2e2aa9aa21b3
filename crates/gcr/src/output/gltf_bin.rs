//! The binary chunk of a .glb under construction — its bytes, bufferViews and accessors, one
//! view per accessor — and the container around it (glTF 2.0 §4.4), shared by the bake
//! (`glb.rs`) and the lightmap (`lightmap.rs`).

use serde_json::{Value, json};

/// The binary chunk: bytes, bufferViews and accessors.
#[derive(Default)]
pub(super) struct Bin {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    /// Appends raw bytes as a bufferView (4-byte aligned; `target` 34962 for vertex attributes,
    /// 34963 for indices, none for images); returns the view.
    pub(super) fn view(&mut self, data: &[u8], target: Option<u32>) -> usize {
        while self.bytes.len() % 4 != 0 {
            self.bytes.push(0);
        }
        let at = self.bytes.len();
        self.bytes.extend_from_slice(data);
        let mut v = json!({"buffer": 0, "byteOffset": at, "byteLength": data.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.views.push(v);
        self.views.len() - 1
    }

    /// Appends an f32 vertex attribute of `N` components (`kind` "VEC2", "VEC3"), with its
    /// bounds when asked (glTF requires them for `POSITION`); returns its accessor.
    pub(super) fn floats<const N: usize>(
        &mut self,
        data: &[[f32; N]],
        kind: &str,
        bounds: bool,
    ) -> usize {
        let raw: Vec<u8> = data
            .iter()
            .flatten()
            .flat_map(|c| c.to_le_bytes())
            .collect();
        let view = self.view(&raw, Some(34962));
        let mut acc = json!({"bufferView": view, "componentType": 5126, "count": data.len(),
            "type": kind});
        if bounds {
            let (mut lo, mut hi) = ([f32::INFINITY; N], [f32::NEG_INFINITY; N]);
            for v in data {
                for k in 0..N {
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
            }
            acc["min"] = json!(lo.to_vec());
            acc["max"] = json!(hi.to_vec());
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    /// Appends u32 triangle indices; returns their accessor.
    pub(super) fn indices(&mut self, tris: &[[u32; 3]]) -> usize {
        let raw: Vec<u8> = tris
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let view = self.view(&raw, Some(34963));
        self.accessors
            .push(json!({"bufferView": view, "componentType": 5125,
            "count": tris.len() * 3, "type": "SCALAR"}));
        self.accessors.len() - 1
    }

    /// Whether nothing was appended.
    pub(super) fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }

    /// The .glb of `doc` with this chunk as its buffer (its `buffers`, `bufferViews` and
    /// `accessors` set here unless the chunk is empty).
    pub(super) fn into_glb(self, mut doc: Value) -> Vec<u8> {
        if !self.is_empty() {
            doc["buffers"] = json!([{"byteLength": self.bytes.len()}]);
            doc["bufferViews"] = json!(self.views);
            doc["accessors"] = json!(self.accessors);
        }
        glb_bytes(&doc, self.bytes)
    }
}

/// The binary container: the JSON chunk padded with spaces, then the buffer's chunk.
fn glb_bytes(doc: &Value, data: Vec<u8>) -> Vec<u8> {
    let mut json = serde_json::to_vec(doc).unwrap_or_default();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut data = data;
    while data.len() % 4 != 0 {
        data.push(0);
    }
    let with_bin = !data.is_empty();
    let total = 12 + 8 + json.len() + if with_bin { 8 + data.len() } else { 0 };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if with_bin {
        out.extend_from_slice(&(data.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&data);
    }
    out
}
