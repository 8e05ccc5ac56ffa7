//! Accessor reads: every byte range checked against its buffer view, and the view against its
//! buffer, before a byte is read; sparse substitution; normalized integers converted.

use ::gltf::json;
use json::accessor::{ComponentType, Type};

use super::importer::{Expect, Importer, Raw};
use crate::import::error::{ImportError, Source};

impl Importer<'_> {
    pub(super) fn accessor_label(&self, index: usize, what: &str) -> String {
        format!("accessor {index} ({what})")
    }

    /// An attribute accessor's values as `f64`, `count * dims` of them, checked for bounds and
    /// finiteness.
    pub(super) fn read_attribute(
        &self,
        index: usize,
        what: &str,
        expect: &Expect,
    ) -> Result<Raw, ImportError> {
        let at = self.accessor_label(index, what);
        let raw = self.read(index, &at)?;
        if !expect.dims.contains(&raw.dims) {
            return Err(self.source.malformed(
                &at,
                format!(
                    "type has {} components; {} needs {}",
                    raw.dims,
                    expect.semantic,
                    expect
                        .dims
                        .iter()
                        .map(|d| d.to_string())
                        .collect::<Vec<_>>()
                        .join(" or ")
                ),
            ));
        }
        if let Some(i) = raw.values.iter().position(|v| !v.is_finite()) {
            return Err(self.source.non_finite(
                at,
                format!("element {} component {}", i / raw.dims, i % raw.dims),
                raw.values[i],
            ));
        }
        Ok(raw)
    }

    pub(super) fn read_indices(&self, index: usize, at: &str) -> Result<Vec<u32>, ImportError> {
        let accessor = &self.root.accessors[index];
        match accessor.component_type {
            json::validation::Checked::Valid(json::accessor::GenericComponentType(
                ComponentType::U8 | ComponentType::U16 | ComponentType::U32,
            )) => {}
            _ => {
                return Err(self
                    .source
                    .malformed(at, "indices must be unsigned bytes, shorts or ints"))
            }
        }
        let raw = self.read(index, at)?;
        if raw.dims != 1 || accessor.normalized {
            return Err(self
                .source
                .malformed(at, "indices must be SCALAR and not normalized"));
        }
        Ok(raw.values.into_iter().map(|v| v as u32).collect())
    }

    /// Reads any accessor: every byte range checked before reading.
    fn read(&self, index: usize, at: &str) -> Result<Raw, ImportError> {
        let source = self.source;
        let accessor = self
            .root
            .accessors
            .get(index)
            .ok_or_else(|| source.malformed(at, "no such accessor"))?;
        let layout = Layout::of(source, accessor, at)?;
        let mut values = match accessor.buffer_view {
            None => zeros(source, accessor, &layout, at)?,
            Some(view) => self.read_view(accessor, view.value(), &layout, at)?,
        };
        if let Some(sparse) = &accessor.sparse {
            self.apply_sparse(sparse, &layout, &mut values, at)?;
        }
        Ok(Raw {
            values,
            dims: layout.dims,
        })
    }

    /// The elements stored in a buffer view, after checking that the last one ends inside it.
    fn read_view(
        &self,
        accessor: &json::Accessor,
        view: usize,
        layout: &Layout,
        at: &str,
    ) -> Result<Vec<f64>, ImportError> {
        let source = self.source;
        let Layout {
            component,
            dims,
            count,
            total,
            size,
            element,
            normalized,
        } = *layout;
        let offset = accessor.byte_offset.map_or(0, |o| o.0);
        let (bytes, stride) = self.view_bytes(view, at)?;
        let stride = stride.unwrap_or(element);
        if stride < element {
            return Err(source.malformed(
                at,
                format!("byteStride {stride} of buffer view {view} is less than the element size {element}"),
            ));
        }
        let need = if count == 0 {
            Some(0)
        } else {
            (count as u64 - 1)
                .checked_mul(stride as u64)
                .and_then(|v| v.checked_add(element as u64))
                .and_then(|v| v.checked_add(offset))
        };
        match need {
            Some(n) if n <= bytes.len() as u64 => {}
            _ => {
                return Err(source.malformed(
                    at,
                    format!(
                        "out of bounds of buffer view {view}: {count} elements of {element} bytes with stride {stride} from byte {offset} need {} bytes, the view has {}",
                        need.map_or("more than 2^64".to_owned(), |n| n.to_string()),
                        bytes.len()
                    ),
                ))
            }
        }
        let offset = offset as usize;
        let mut values = Vec::with_capacity(total);
        for e in 0..count {
            let start = offset + e * stride;
            for c in 0..dims {
                let at = start + c * size;
                values.push(decode(component, normalized, &bytes[at..at + size]));
            }
        }
        Ok(values)
    }

    /// Substitutes the sparse elements, their indices and values checked against their views
    /// and every index against the accessor's count.
    fn apply_sparse(
        &self,
        sparse: &json::accessor::sparse::Sparse,
        layout: &Layout,
        values: &mut [f64],
        at: &str,
    ) -> Result<(), ImportError> {
        let source = self.source;
        let Layout {
            component,
            dims,
            count,
            size,
            element,
            normalized,
            ..
        } = *layout;
        let n = usize::try_from(sparse.count.0)
            .map_err(|_| source.malformed(at, "sparse count too large"))?;
        let index_type = match sparse.indices.component_type {
            json::validation::Checked::Valid(json::accessor::IndexComponentType(c)) => c,
            json::validation::Checked::Invalid => {
                return Err(source.malformed(at, "invalid sparse index componentType"))
            }
        };
        let isize_ = component_size(index_type);
        let (ibytes, _) = self.view_bytes(sparse.indices.buffer_view.value(), at)?;
        let (vbytes, _) = self.view_bytes(sparse.values.buffer_view.value(), at)?;
        let ioff = sparse.indices.byte_offset.0;
        let voff = sparse.values.byte_offset.0;
        let fits = |off: u64, per: usize, len: usize| {
            (n as u64)
                .checked_mul(per as u64)
                .and_then(|v| v.checked_add(off))
                .is_some_and(|end| end <= len as u64)
        };
        if !fits(ioff, isize_, ibytes.len()) || !fits(voff, element, vbytes.len()) {
            return Err(source.malformed(
                at,
                format!(
                    "sparse indices or values ({n} of them) out of bounds of their buffer views"
                ),
            ));
        }
        let (ioff, voff) = (ioff as usize, voff as usize);
        for k in 0..n {
            let i0 = ioff + k * isize_;
            let target = decode(index_type, false, &ibytes[i0..i0 + isize_]) as usize;
            if target >= count {
                return Err(source.out_of_range(
                    at,
                    "sparse index",
                    target as i64,
                    count,
                    "elements",
                ));
            }
            for c in 0..dims {
                let v0 = voff + k * element + c * size;
                values[target * dims + c] = decode(component, normalized, &vbytes[v0..v0 + size]);
            }
        }
        Ok(())
    }

    /// A buffer view's bytes (checked against its buffer) and its stride.
    pub(super) fn view_bytes(
        &self,
        view: usize,
        at: &str,
    ) -> Result<(&[u8], Option<usize>), ImportError> {
        let source = self.source;
        let json = self
            .root
            .buffer_views
            .get(view)
            .ok_or_else(|| source.malformed(at, format!("no buffer view {view}")))?;
        let buffer = json.buffer.value();
        let data = self.buffers.get(buffer).ok_or_else(|| {
            source.malformed(format!("buffer view {view}"), format!("no buffer {buffer}"))
        })?;
        let declared = self.root.buffers.get(buffer).map_or(0, |b| b.byte_length.0);
        let start = json.byte_offset.map_or(0, |o| o.0);
        let end = start.checked_add(json.byte_length.0);
        match end {
            Some(end) if end <= declared && end <= data.len() as u64 => {}
            _ => {
                return Err(source.malformed(
                    format!("buffer view {view}"),
                    format!(
                        "bytes {start}..{} out of bounds of buffer {buffer} ({declared} bytes)",
                        end.map_or("overflow".to_owned(), |e| e.to_string())
                    ),
                ))
            }
        }
        let stride = json.byte_stride.map(|s| s.0).filter(|&s| s != 0);
        Ok((
            &data[start as usize..(start + json.byte_length.0) as usize],
            stride,
        ))
    }
}

/// An accessor's element layout: component type, components per element, element count, value
/// count, component and element sizes in bytes, and whether integers are normalized.
#[derive(Clone, Copy)]
struct Layout {
    component: ComponentType,
    dims: usize,
    count: usize,
    total: usize,
    size: usize,
    element: usize,
    normalized: bool,
}

impl Layout {
    fn of(source: &Source, accessor: &json::Accessor, at: &str) -> Result<Self, ImportError> {
        let component = match accessor.component_type {
            json::validation::Checked::Valid(json::accessor::GenericComponentType(c)) => c,
            json::validation::Checked::Invalid => {
                return Err(source.malformed(at, "invalid componentType"))
            }
        };
        let dims = match accessor.type_ {
            json::validation::Checked::Valid(t) => type_dims(t).ok_or_else(|| {
                source.unsupported(at, "matrix accessors are not vertex attributes")
            })?,
            json::validation::Checked::Invalid => return Err(source.malformed(at, "invalid type")),
        };
        let count = usize::try_from(accessor.count.0)
            .map_err(|_| source.malformed(at, "count too large"))?;
        let total = count
            .checked_mul(dims)
            .ok_or_else(|| source.malformed(at, "count too large"))?;
        let size = component_size(component);
        Ok(Layout {
            component,
            dims,
            count,
            total,
            size,
            element: size * dims,
            normalized: accessor.normalized,
        })
    }
}

/// An accessor without a buffer view: all zeros (then sparse substitution), as the
/// specification says. A huge count without any data behind it is not a reason to allocate
/// gigabytes.
fn zeros(
    source: &Source,
    accessor: &json::Accessor,
    layout: &Layout,
    at: &str,
) -> Result<Vec<f64>, ImportError> {
    if accessor.sparse.is_none() {
        return Err(source.malformed(at, "no bufferView and no sparse data"));
    }
    if layout.total > (1 << 24) {
        let count = layout.count;
        return Err(source.malformed(at, format!("count {count} without a bufferView")));
    }
    Ok(vec![0.0; layout.total])
}

fn type_dims(t: Type) -> Option<usize> {
    match t {
        Type::Scalar => Some(1),
        Type::Vec2 => Some(2),
        Type::Vec3 => Some(3),
        Type::Vec4 => Some(4),
        Type::Mat2 | Type::Mat3 | Type::Mat4 => None,
    }
}

fn component_size(c: ComponentType) -> usize {
    match c {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

/// One little-endian component, normalized integers mapped as the specification says.
fn decode(c: ComponentType, normalized: bool, b: &[u8]) -> f64 {
    match c {
        ComponentType::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        ComponentType::U8 => {
            let v = f64::from(b[0]);
            if normalized {
                v / 255.0
            } else {
                v
            }
        }
        ComponentType::I8 => {
            let v = f64::from(b[0] as i8);
            if normalized {
                (v / 127.0).max(-1.0)
            } else {
                v
            }
        }
        ComponentType::U16 => {
            let v = f64::from(u16::from_le_bytes([b[0], b[1]]));
            if normalized {
                v / 65535.0
            } else {
                v
            }
        }
        ComponentType::I16 => {
            let v = f64::from(i16::from_le_bytes([b[0], b[1]]));
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        ComponentType::U32 => {
            let v = f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
            if normalized {
                v / f64::from(u32::MAX)
            } else {
                v
            }
        }
    }
}
