//! Decoding accessors (glTF 2.0 §3.6.2) into `f64`s, for every component type.
//!
//! The `gltf` crate's readers take only the component types of core glTF for each attribute
//! and read the buffer behind a meshopt-compressed view; this reads any accessor: its buffer
//! view's bytes (the decoded ones for a compressed view) with the view's `byteStride`, every
//! component type, the `normalized` mapping of §3.11 (`i8`: max(c / 127, −1), `u8`: c / 255,
//! `i16`: max(c / 32767, −1), `u16`: c / 65535), no view (all zeros), and sparse
//! substitution (§3.6.2.3).

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::Accessor;

/// The bytes of the buffers and of the decoded (meshopt) buffer views.
pub(crate) struct Data<'a> {
    pub buffers: &'a [Vec<u8>],
    pub views: &'a [Option<Vec<u8>>],
}

impl Data<'_> {
    /// The bytes of a buffer view, or a message.
    fn view(&self, view: &::gltf::buffer::View) -> Result<&[u8], String> {
        if let Some(Some(d)) = self.views.get(view.index()) {
            return Ok(d);
        }
        let (o, n) = (view.offset(), view.length());
        self.buffers
            .get(view.buffer().index())
            .and_then(|b| b.get(o..o.checked_add(n)?))
            .ok_or_else(|| {
                format!(
                    "buffer view {} (bytes {o}..+{n} of buffer {}) is not in the file",
                    view.index(),
                    view.buffer().index()
                )
            })
    }
}

/// Number of components of an element.
pub(crate) fn components(d: Dimensions) -> usize {
    d.multiplicity()
}

fn size(t: DataType) -> usize {
    match t {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

/// One component at the start of `b`.
fn component(b: &[u8], t: DataType, normalized: bool) -> f64 {
    match (t, normalized) {
        (DataType::F32, _) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        (DataType::U32, _) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        (DataType::I8, false) => b[0] as i8 as f64,
        (DataType::I8, true) => (b[0] as i8 as f64 / 127.0).max(-1.0),
        (DataType::U8, false) => b[0] as f64,
        (DataType::U8, true) => b[0] as f64 / 255.0,
        (DataType::I16, n) => {
            let c = i16::from_le_bytes([b[0], b[1]]) as f64;
            if n {
                (c / 32767.0).max(-1.0)
            } else {
                c
            }
        }
        (DataType::U16, n) => {
            let c = u16::from_le_bytes([b[0], b[1]]) as f64;
            if n {
                c / 65535.0
            } else {
                c
            }
        }
    }
}

/// Room for `n` more values in `out`, or a message (never an abort).
pub(crate) fn reserve<T>(out: &mut Vec<T>, n: usize) -> Result<(), String> {
    out.try_reserve_exact(n).map_err(|e| {
        format!(
            "cannot allocate {n} values of {} bytes: {e}",
            std::mem::size_of::<T>()
        )
    })
}

/// Reads `count` elements of `comps` components of type `t` from `bytes` at `offset`, each
/// `stride` bytes apart (tightly packed when `None`).
#[allow(clippy::too_many_arguments)]
fn read_dense(
    bytes: &[u8],
    offset: usize,
    stride: Option<usize>,
    count: usize,
    comps: usize,
    t: DataType,
    normalized: bool,
    out: &mut Vec<f64>,
) -> Result<(), String> {
    if count == 0 {
        return Ok(());
    }
    let elem = comps * size(t);
    let stride = stride.unwrap_or(elem);
    if stride < elem {
        return Err(format!(
            "byteStride {stride} is smaller than an element ({elem} bytes)"
        ));
    }
    (count - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(offset)?.checked_add(elem))
        .filter(|&n| n <= bytes.len())
        .ok_or_else(|| {
            format!(
                "{count} elements of {elem} bytes (stride {stride}, offset {offset}) need more than the {} bytes of its buffer view",
                bytes.len()
            )
        })?;
    reserve(out, count * comps)?;
    for i in 0..count {
        let e = &bytes[offset + i * stride..];
        for c in 0..comps {
            out.push(component(&e[c * size(t)..], t, normalized));
        }
    }
    Ok(())
}

/// All components of accessor `acc` (`count × components`), decoded to `f64`; errors are
/// messages naming the accessor.
pub(crate) fn read(acc: &Accessor, data: &Data) -> Result<Vec<f64>, String> {
    let at = |m: String| format!("accessor {}: {m}", acc.index());
    let (count, t, norm) = (acc.count(), acc.data_type(), acc.normalized());
    if count == 0 {
        return Err(at("count 0; glTF requires at least 1".into()));
    }
    let comps = components(acc.dimensions());
    if matches!(
        acc.dimensions(),
        Dimensions::Mat2 | Dimensions::Mat3 | Dimensions::Mat4
    ) {
        return Err(at("matrix accessors are not read".into()));
    }
    let mut out = Vec::new();
    match acc.view() {
        Some(view) => {
            let bytes = data.view(&view).map_err(at)?;
            read_dense(
                bytes,
                acc.offset(),
                view.stride(),
                count,
                comps,
                t,
                norm,
                &mut out,
            )
            .map_err(at)?;
        }
        None => {
            // No buffer view: all zeros (§5.1.1), with sparse values if any. The count is the
            // document's word: the file's decoding budget (`budget.rs`) bounded it, and an
            // allocation that still fails is an error.
            let n = count
                .checked_mul(comps)
                .ok_or_else(|| at(format!("{count} elements without a buffer view")))?;
            reserve(&mut out, n).map_err(at)?;
            out.resize(n, 0.0);
        }
    }
    if let Some(sp) = acc.sparse() {
        let n = sp.count();
        let (iv, vv) = (sp.indices(), sp.values());
        let it = match iv.index_type() {
            ::gltf::accessor::sparse::IndexType::U8 => DataType::U8,
            ::gltf::accessor::sparse::IndexType::U16 => DataType::U16,
            ::gltf::accessor::sparse::IndexType::U32 => DataType::U32,
        };
        let mut idx = Vec::new();
        let ib = data.view(&iv.view()).map_err(at)?;
        read_dense(ib, iv.offset(), None, n, 1, it, false, &mut idx)
            .map_err(|m| at(format!("sparse indices: {m}")))?;
        let mut vals = Vec::new();
        let vb = data.view(&vv.view()).map_err(at)?;
        read_dense(vb, vv.offset(), None, n, comps, t, norm, &mut vals)
            .map_err(|m| at(format!("sparse values: {m}")))?;
        for (k, &i) in idx.iter().enumerate() {
            let i = i as usize;
            if i >= count {
                return Err(at(format!(
                    "sparse index {k} is {i}, but the accessor has {count} elements"
                )));
            }
            out[i * comps..(i + 1) * comps].copy_from_slice(&vals[k * comps..(k + 1) * comps]);
        }
    }
    Ok(out)
}

/// Accessor `acc` as 3-vectors; errors when it is not `VEC3`.
pub(crate) fn read_vec3(acc: &Accessor, data: &Data) -> Result<Vec<[f64; 3]>, String> {
    if acc.dimensions() != Dimensions::Vec3 {
        return Err(format!(
            "accessor {} is {:?} {:?}, expected VEC3",
            acc.index(),
            acc.data_type(),
            acc.dimensions()
        ));
    }
    if acc.data_type() == DataType::U32 {
        return Err(format!(
            "accessor {} has component type u32, which glTF allows only for indices",
            acc.index()
        ));
    }
    let v = read(acc, data)?;
    let mut out = Vec::new();
    reserve(&mut out, v.len() / 3).map_err(|m| format!("accessor {}: {m}", acc.index()))?;
    out.extend(v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
    Ok(out)
}
