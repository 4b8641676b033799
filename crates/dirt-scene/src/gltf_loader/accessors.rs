//! Accessor decoding: float attributes and index lists read from buffer
//! views (including sparse substitution) with bounds-checked arithmetic,
//! rather than with `gltf`'s reader, which trusts offsets and component
//! types.

use gltf::accessor::{DataType, Dimensions};

use super::Ctx;
use crate::SceneError;

/// Largest number of components one accessor may decode to (1 GiB of f32);
/// only view-less (all-zero or sparse) accessors can claim more than their
/// buffer holds, and they are refused beyond this.
const MAX_ACCESSOR_COMPONENTS: usize = 1 << 28;
/// Reads a float attribute (`dims` components per element) as `f32`,
/// accepting float components and (normalised or not) integer ones
/// (`KHR_mesh_quantization` style).
pub(super) fn read_floats(
    ctx: &Ctx,
    acc: &gltf::Accessor,
    dims: Dimensions,
    location: &str,
    attribute: &str,
) -> Result<Vec<f32>, SceneError> {
    if acc.dimensions() != dims {
        return Err(ctx.accessor_err(
            location,
            attribute,
            format!(
                "accessor {} has type {:?}, expected {dims:?}",
                acc.index(),
                acc.dimensions()
            ),
        ));
    }
    let raw =
        read_accessor(ctx.buffers, acc).map_err(|p| ctx.accessor_err(location, attribute, p))?;
    let dt = acc.data_type();
    let norm = acc.normalized();
    Ok(raw
        .into_iter()
        .map(|v| match (dt, norm) {
            (DataType::U8, true) => (v / 255.0) as f32,
            (DataType::U16, true) => (v / 65535.0) as f32,
            (DataType::U32, true) => (v / 4294967295.0) as f32,
            (DataType::I8, true) => (v / 127.0).max(-1.0) as f32,
            (DataType::I16, true) => (v / 32767.0).max(-1.0) as f32,
            _ => v as f32,
        })
        .collect())
}

/// Reads an index accessor (scalar `u8`/`u16`/`u32`).
pub(super) fn read_indices(
    ctx: &Ctx,
    acc: &gltf::Accessor,
    location: &str,
) -> Result<Vec<u32>, SceneError> {
    let err = |p| ctx.accessor_err(location, "indices", p);
    if acc.dimensions() != Dimensions::Scalar {
        return Err(err(format!(
            "accessor {} has type {:?}, expected Scalar",
            acc.index(),
            acc.dimensions()
        )));
    }
    if !matches!(
        acc.data_type(),
        DataType::U8 | DataType::U16 | DataType::U32
    ) {
        return Err(err(format!(
            "accessor {} has component type {:?}, expected U8, U16 or U32",
            acc.index(),
            acc.data_type()
        )));
    }
    let raw = read_accessor(ctx.buffers, acc).map_err(err)?;
    Ok(raw.into_iter().map(|v| v as u32).collect())
}

fn component_size(dt: DataType) -> usize {
    match dt {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

/// Decodes one little-endian component (exactly representable in `f64`).
fn component(bytes: &[u8], off: usize, dt: DataType) -> Option<f64> {
    let b = |n: usize| bytes.get(off..off.checked_add(n)?);
    Some(match dt {
        DataType::I8 => i8::from_le_bytes(b(1)?.try_into().ok()?) as f64,
        DataType::U8 => u8::from_le_bytes(b(1)?.try_into().ok()?) as f64,
        DataType::I16 => i16::from_le_bytes(b(2)?.try_into().ok()?) as f64,
        DataType::U16 => u16::from_le_bytes(b(2)?.try_into().ok()?) as f64,
        DataType::U32 => u32::from_le_bytes(b(4)?.try_into().ok()?) as f64,
        DataType::F32 => f32::from_le_bytes(b(4)?.try_into().ok()?) as f64,
    })
}

/// The bytes of a buffer view.
fn view_bytes<'b>(
    buffers: &'b [gltf::buffer::Data],
    view: &gltf::buffer::View,
) -> Result<&'b [u8], String> {
    let data = buffers
        .get(view.buffer().index())
        .ok_or_else(|| format!("buffer {} not loaded", view.buffer().index()))?;
    let start = view.offset();
    let end = start.checked_add(view.length());
    end.and_then(|end| data.get(start..end)).ok_or_else(|| {
        format!(
            "buffer view {} (offset {}, length {}) exceeds buffer {} ({} bytes)",
            view.index(),
            start,
            view.length(),
            view.buffer().index(),
            data.len()
        )
    })
}

/// Reads `count` elements of `n` components of type `dt` starting at
/// `offset` with `stride` from `bytes`, appending them to `out` (or, with
/// `targets`, writing element `k` at element position `targets[k]`).
fn read_elements(
    bytes: &[u8],
    offset: usize,
    stride: usize,
    count: usize,
    n: usize,
    dt: DataType,
    mut sink: impl FnMut(usize, usize, f64),
) -> Result<(), String> {
    let elem = n * component_size(dt);
    if count == 0 {
        return Ok(());
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(offset))
        .and_then(|x| x.checked_add(elem))
        .ok_or_else(|| "element range overflows".to_string())?;
    if end > bytes.len() {
        return Err(format!(
            "{count} elements of {elem} bytes (stride {stride}, offset {offset}) need {end} bytes, \
             the buffer view has {}",
            bytes.len()
        ));
    }
    for k in 0..count {
        let base = offset + k * stride;
        for c in 0..n {
            let v = component(bytes, base + c * component_size(dt), dt)
                .ok_or("read past the end of the buffer view")?;
            sink(k, c, v);
        }
    }
    Ok(())
}

/// Decodes an accessor (including sparse substitution) to `count * n`
/// components, with every offset, stride and index checked.
fn read_accessor(buffers: &[gltf::buffer::Data], acc: &gltf::Accessor) -> Result<Vec<f64>, String> {
    let dims = acc.dimensions();
    // Matrix columns of 1- and 2-byte components are padded to 4 bytes;
    // only 4-byte components (inverse bind matrices are float) are packed.
    if matches!(dims, Dimensions::Mat2 | Dimensions::Mat3 | Dimensions::Mat4)
        && component_size(acc.data_type()) != 4
    {
        return Err(format!(
            "accessor {}: matrix accessors of 1- or 2-byte components are not supported",
            acc.index()
        ));
    }
    let n = dims.multiplicity();
    let dt = acc.data_type();
    let elem = n * component_size(dt);
    let count = acc.count();
    let total = count
        .checked_mul(n)
        .filter(|&t| t <= MAX_ACCESSOR_COMPONENTS)
        .ok_or_else(|| format!("accessor {}: count {count} is too large", acc.index()))?;
    let ctx = |e: String| format!("accessor {}: {e}", acc.index());

    let mut out = vec![0.0f64; 0];
    if let Some(view) = acc.view() {
        let bytes = view_bytes(buffers, &view).map_err(ctx)?;
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(ctx(format!(
                "byte stride {stride} is smaller than the element size {elem}"
            )));
        }
        out.reserve_exact(total);
        read_elements(bytes, acc.offset(), stride, count, n, dt, |_, _, v| {
            out.push(v)
        })
        .map_err(ctx)?;
    } else {
        out = vec![0.0; total];
    }

    if let Some(sparse) = acc.sparse() {
        let sc = sparse.count();
        if sc > count {
            return Err(ctx(format!(
                "sparse count {sc} exceeds accessor count {count}"
            )));
        }
        let idx = sparse.indices();
        let idx_dt = match idx.index_type() {
            gltf::accessor::sparse::IndexType::U8 => DataType::U8,
            gltf::accessor::sparse::IndexType::U16 => DataType::U16,
            gltf::accessor::sparse::IndexType::U32 => DataType::U32,
        };
        let idx_bytes = view_bytes(buffers, &idx.view()).map_err(ctx)?;
        let mut targets = Vec::with_capacity(sc);
        read_elements(
            idx_bytes,
            idx.offset(),
            component_size(idx_dt),
            sc,
            1,
            idx_dt,
            |_, _, v| targets.push(v as usize),
        )
        .map_err(|e| ctx(format!("sparse indices: {e}")))?;
        if let Some(&bad) = targets.iter().find(|&&t| t >= count) {
            return Err(ctx(format!(
                "sparse index {bad} is out of range (count {count})"
            )));
        }
        let vals = sparse.values();
        let val_bytes = view_bytes(buffers, &vals.view()).map_err(ctx)?;
        let mut bad_slot = false;
        read_elements(
            val_bytes,
            vals.offset(),
            elem,
            sc,
            n,
            dt,
            |k, c, v| match targets.get(k).and_then(|&t| out.get_mut(t * n + c)) {
                Some(slot) => *slot = v,
                None => bad_slot = true,
            },
        )
        .map_err(|e| ctx(format!("sparse values: {e}")))?;
        if bad_slot {
            return Err(ctx("sparse substitution out of range".to_string()));
        }
    }
    Ok(out)
}
