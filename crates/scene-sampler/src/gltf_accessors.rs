//! glTF accessors checked against their buffer views and buffers before anything is read
//! (glTF 2.0 §3.6 "Binary data storage", §3.7.2.1 "Meshes").
//!
//! The gltf crate's reader gives `None` for an accessor whose data does not fit its view, and a
//! primitive whose index accessor reads `None` is taken as non-indexed: half of every quad would
//! go missing in silence. A view's `byteStride` smaller than its element panics inside the
//! reader, and a sparse index past the accessor's count is skipped. So every accessor a triangle
//! primitive uses (its attributes and indices) is checked here first, against the rules of the
//! specification, and an invalid one is an error naming the accessor, the mesh and what is wrong:
//!
//! - the element (component size × components) fits: `accessor.byteOffset + stride·(count − 1) +
//!   element ≤ view.byteLength`, and the view fits its buffer's data;
//! - `accessor.byteOffset` is a multiple of the component size, `count ≥ 1`;
//! - a view's `byteStride` is at least the element, at most 252 and a multiple of 4; index views
//!   have none (§3.7.2.1);
//! - POSITION is `VEC3` of floats; TEXCOORD_n `VEC2` of floats or normalised unsigned bytes or
//!   shorts; indices are `SCALAR` unsigned bytes, shorts or ints; all attributes of a primitive
//!   have the same count;
//! - sparse storage: at most `count` substitutions, their indices strictly increasing and below
//!   `count` (§3.6.2.3), both views within bounds.
//!
//! Also here: [`parser_prechecks`], run before the document is validated, for what the gltf
//! crate reads without a check (and panics on): a POSITION naming no accessor, an image without
//! a source.

use crate::{Result, SceneError};
use gltf::accessor::{DataType, Dimensions};
use gltf::json::mesh::Semantic;

/// What the gltf crate reads unchecked, checked first: the POSITION accessor of every
/// primitive exists (its validation indexes it and panics), and every image has a `uri` or a
/// `bufferView` with a `mimeType` (asking it for its source panics); else an error naming the
/// mesh or the image.
pub(crate) fn parser_prechecks(root: &gltf::json::Root, source: &str) -> Result<()> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let key = gltf::json::validation::Checked::Valid(Semantic::Positions);
            if let Some(index) = prim.attributes.get(&key) {
                if index.value() >= root.accessors.len() {
                    return Err(malformed(
                        source,
                        format!(
                            "mesh {m} primitive {p}: POSITION names accessor {}, \
                             but the file has {} accessors",
                            index.value(),
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    for (i, image) in root.images.iter().enumerate() {
        let sourced = match image.buffer_view {
            Some(_) => image.mime_type.is_some(),
            None => image.uri.is_some(),
        };
        if !sourced {
            return Err(malformed(
                source,
                format!("image {i}: neither a `uri` nor a `bufferView` with a `mimeType`"),
            ));
        }
    }
    Ok(())
}

/// Checks every accessor triangle primitive `prim` of mesh `mesh` uses against its views and
/// `buffers` (the buffers' data): see the module documentation for the rules.
pub(crate) fn check_primitive(
    prim: &gltf::Primitive,
    mesh: &str,
    buffers: &[Vec<u8>],
    source: &str,
) -> Result<()> {
    let mut count = None;
    for (semantic, accessor) in prim.attributes() {
        let role = semantic.to_string();
        let at = Where {
            source,
            mesh,
            role: &role,
            accessor: accessor.index(),
        };
        if semantic == gltf::Semantic::Positions
            && (accessor.dimensions() != Dimensions::Vec3 || accessor.data_type() != DataType::F32)
        {
            return Err(at.error(format!(
                "POSITION must be VEC3 of floats, not {:?} of {:?}",
                accessor.dimensions(),
                accessor.data_type()
            )));
        }
        let coordinates = matches!(
            accessor.data_type(),
            DataType::F32 | DataType::U8 | DataType::U16
        );
        if matches!(semantic, gltf::Semantic::TexCoords(_))
            && (accessor.dimensions() != Dimensions::Vec2 || !coordinates)
        {
            return Err(at.error(format!(
                "texture coordinates must be VEC2 of floats or normalised unsigned bytes or \
                 shorts, not {:?} of {:?}",
                accessor.dimensions(),
                accessor.data_type()
            )));
        }
        check_accessor(&accessor, &at, buffers, false)?;
        match count {
            None => count = Some((accessor.count(), role)),
            Some((n, ref first)) if n != accessor.count() => {
                return Err(at.error(format!(
                    "{} elements, but {first} has {n}: a primitive's attributes must \
                     have the same count",
                    accessor.count()
                )));
            }
            Some(_) => {}
        }
    }
    if let Some(indices) = prim.indices() {
        let at = Where {
            source,
            mesh,
            role: "indices",
            accessor: indices.index(),
        };
        let unsigned = matches!(
            indices.data_type(),
            DataType::U8 | DataType::U16 | DataType::U32
        );
        if indices.dimensions() != Dimensions::Scalar || !unsigned {
            return Err(at.error(format!(
                "indices must be SCALAR unsigned bytes, shorts or ints, not {:?} of {:?}",
                indices.dimensions(),
                indices.data_type()
            )));
        }
        check_accessor(&indices, &at, buffers, true)?;
    }
    Ok(())
}

/// An accessor's place, for messages: the scene file, the mesh, its role in the primitive and
/// its index.
struct Where<'a> {
    source: &'a str,
    mesh: &'a str,
    role: &'a str,
    accessor: usize,
}

impl Where<'_> {
    fn error(&self, what: String) -> SceneError {
        malformed(
            self.source,
            format!(
                "mesh `{}`: accessor {} ({}): {what}",
                self.mesh, self.accessor, self.role
            ),
        )
    }
}

fn malformed(source: &str, message: String) -> SceneError {
    SceneError::Parse {
        source_name: source.into(),
        message,
    }
}

/// Checks `accessor` (at `at`; `indices`: used as a primitive's indices) and its sparse storage
/// against their views and `buffers`.
fn check_accessor(
    accessor: &gltf::Accessor,
    at: &Where,
    buffers: &[Vec<u8>],
    indices: bool,
) -> Result<()> {
    let component = accessor.data_type().size();
    let element = accessor.size();
    let count = accessor.count();
    if count == 0 {
        return Err(at.error("count is 0 (glTF requires at least 1)".into()));
    }
    if let Some(view) = accessor.view() {
        let stride = checked_stride(&view, element, indices, at)?;
        let offset = accessor.offset();
        if offset % component != 0 {
            return Err(at.error(format!(
                "byteOffset {offset} is not a multiple of its component size {component}"
            )));
        }
        let need = (stride as u128) * (count as u128 - 1) + (offset + element) as u128;
        if need > view.length() as u128 {
            return Err(at.error(format!(
                "{count} elements of {element} bytes (stride {stride}) from byteOffset {offset} \
                 need {need} bytes, but bufferView {} has {}",
                view.index(),
                view.length()
            )));
        }
        check_view(&view, buffers, at)?;
    }
    if let Some(sparse) = accessor.sparse() {
        check_sparse(&sparse, count, element, buffers, at)?;
    }
    Ok(())
}

/// The stride of `view` for elements of `element` bytes, checked (`indices`: the view holds a
/// primitive's indices, which must be tightly packed).
fn checked_stride(
    view: &gltf::buffer::View,
    element: usize,
    indices: bool,
    at: &Where,
) -> Result<usize> {
    let Some(stride) = view.stride() else {
        return Ok(element);
    };
    let v = view.index();
    if indices {
        return Err(at.error(format!(
            "bufferView {v} of indices has a byteStride ({stride}); index data must be \
             tightly packed"
        )));
    }
    if stride < element || stride > 252 || stride % 4 != 0 {
        return Err(at.error(format!(
            "bufferView {v}: byteStride {stride} for elements of {element} bytes (it must be \
             at least the element, at most 252 and a multiple of 4)"
        )));
    }
    Ok(stride)
}

/// `view` lies within its buffer's data.
fn check_view(view: &gltf::buffer::View, buffers: &[Vec<u8>], at: &Where) -> Result<()> {
    let b = view.buffer().index();
    let have = buffers.get(b).map_or(0, Vec::len) as u128;
    let end = view.offset() as u128 + view.length() as u128;
    if end > have {
        return Err(at.error(format!(
            "bufferView {} ends at byte {end}, but buffer {b} has {have} bytes",
            view.index()
        )));
    }
    Ok(())
}

/// The sparse storage `sparse` of an accessor of `count` elements of `element` bytes: its index
/// and value views within bounds, its indices strictly increasing and below `count`.
fn check_sparse(
    sparse: &gltf::accessor::sparse::Sparse,
    count: usize,
    element: usize,
    buffers: &[Vec<u8>],
    at: &Where,
) -> Result<()> {
    use gltf::accessor::sparse::IndexType;
    let n = sparse.count();
    if n == 0 || n > count {
        return Err(at.error(format!(
            "sparse count {n} (it must be 1 to the accessor's count {count})"
        )));
    }
    let (idx, values) = (sparse.indices(), sparse.values());
    let size = match idx.index_type() {
        IndexType::U8 => 1,
        IndexType::U16 => 2,
        IndexType::U32 => 4,
    };
    for (view, offset, bytes, what) in [
        (idx.view(), idx.offset(), n * size, "indices"),
        (values.view(), values.offset(), n * element, "values"),
    ] {
        if view.stride().is_some() {
            return Err(at.error(format!(
                "sparse {what}' bufferView {} has a byteStride; sparse data must be tightly packed",
                view.index()
            )));
        }
        if (offset + bytes) as u128 > view.length() as u128 {
            return Err(at.error(format!(
                "sparse {what}: {bytes} bytes from byteOffset {offset}, but bufferView {} has {}",
                view.index(),
                view.length()
            )));
        }
        check_view(&view, buffers, at)?;
    }
    // ⟨The indices themselves: strictly increasing, each below count⟩
    let view = idx.view();
    let data = &buffers[view.buffer().index()];
    let start = view.offset() + idx.offset();
    let mut last = None;
    for k in 0..n {
        let b = &data[start + k * size..start + (k + 1) * size];
        let i = b.iter().rev().fold(0u64, |v, &x| v << 8 | u64::from(x));
        if i >= count as u64 || last.is_some_and(|l| i <= l) {
            return Err(at.error(format!(
                "sparse index {k} is {i}: sparse indices must increase strictly and stay \
                 below the count {count}"
            )));
        }
        last = Some(i);
    }
    Ok(())
}
