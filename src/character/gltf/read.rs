//! The file and its buffers: the GLB's binary chunk, `data:` URIs, or
//! files beside the glTF (inside its folder only), each checked against
//! the length the file declares; accessors checked against their views
//! before anything is read through them.

use std::path::{Component, Path, PathBuf};

use super::{GltfError, MAX_DATA_BYTES, MAX_FILE_BYTES, MAX_TRIANGLES, MAX_VERTICES};
use crate::reading::ReadError;

/// A parsed, validated glTF document and its buffers' bytes.
pub(super) struct File {
    pub(super) path: PathBuf,
    pub(super) doc: gltf::Document,
    pub(super) buffers: Vec<Vec<u8>>,
    /// The document's root `extensions` where it uses VRM's (the humanoid
    /// map and the credits).
    pub(super) extensions: Option<serde_json::Value>,
}

impl File {
    pub(super) fn open(path: &Path) -> Result<Self, GltfError> {
        let io = |source| GltfError::Io {
            path: path.to_owned(),
            source,
        };
        let data = match crate::reading::read(path, MAX_FILE_BYTES) {
            Ok(d) => d,
            Err(crate::reading::ReadError::TooLarge { said, .. }) => {
                return Err(GltfError::TooBig {
                    path: path.to_owned(),
                    bytes: said,
                    max: MAX_FILE_BYTES,
                });
            }
            Err(e) => return Err(io(e.into())),
        };
        Self::parse(path, &data)
    }

    /// The document in `data`, read as the file `path` (whose folder holds
    /// any buffer files it names).
    pub(super) fn parse(path: &Path, data: &[u8]) -> Result<Self, GltfError> {
        refuse_what_the_reader_would_trip_on(path, data)?;
        let gltf = gltf::Gltf::from_slice(data).map_err(|e| GltfError::NotGltf {
            path: path.to_owned(),
            why: e.to_string(),
        })?;
        let mut buffers = Vec::new();
        for b in gltf.document.buffers() {
            let data = buffer_data(path, &gltf, &b)?;
            buffers.push(data);
        }
        let extensions = gltf
            .document
            .extensions_used()
            .any(|e| e == "VRM" || e == "VRMC_vrm")
            .then(|| root_extensions(data))
            .flatten();
        Ok(Self {
            path: path.to_owned(),
            doc: gltf.document,
            buffers,
            extensions,
        })
    }

    pub(super) fn data_error(&self, why: String) -> GltfError {
        GltfError::Data {
            path: self.path.clone(),
            why,
        }
    }

    /// The bytes of buffer `b`, for the accessor readers.
    pub(super) fn buffer(&self, b: gltf::Buffer<'_>) -> Option<&[u8]> {
        self.buffers.get(b.index()).map(Vec::as_slice)
    }

    /// Checks that accessor `a` can be read whole as it says (dense, at
    /// least one element, inside its view and its view inside its buffer)
    /// and adds what reading it allocates to `budget`, refusing past its
    /// bounds.
    pub(super) fn check(
        &self,
        a: &gltf::Accessor<'_>,
        what: &str,
        kind: Kind,
        budget: &mut Budget,
    ) -> Result<(), GltfError> {
        let bad = |why: String| self.data_error(format!("{what} (accessor {}): {why}", a.index()));
        // The element type the reader of this data expects: any other is
        // read at the wrong size.
        use gltf::accessor::{DataType as T, Dimensions as D};
        let (dims, types): (D, &[T]) = match kind {
            Kind::Points => (D::Vec3, &[T::F32]),
            Kind::Joints => (D::Vec4, &[T::U8, T::U16]),
            Kind::Weights => (D::Vec4, &[T::F32, T::U8, T::U16]),
            Kind::Indices => (D::Scalar, &[T::U8, T::U16, T::U32]),
            Kind::Matrices => (D::Mat4, &[T::F32]),
            Kind::Uvs => (D::Vec2, &[T::F32, T::U8, T::U16]),
        };
        if a.dimensions() != dims || !types.contains(&a.data_type()) {
            return Err(bad(format!(
                "{:?} of {:?}, where {dims:?} of {types:?} is read",
                a.dimensions(),
                a.data_type()
            )));
        }
        if a.sparse().is_some() {
            return Err(bad("sparse accessors are not read".to_owned()));
        }
        let view = a.view().ok_or_else(|| bad("no buffer view".to_owned()))?;
        let (count, size) = (a.count() as u64, a.size() as u64);
        if count == 0 {
            return Err(bad("no elements".to_owned()));
        }
        if let Some(over) = budget.add(kind, count) {
            return Err(bad(over));
        }
        let stride = view.stride().map_or(size, |s| s as u64);
        if stride < size {
            return Err(bad(format!(
                "its view's stride ({stride} bytes) is shorter than an element ({size} bytes)"
            )));
        }
        let end = (count - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(size))
            .and_then(|x| x.checked_add(a.offset() as u64));
        if end.is_none_or(|e| e > view.length() as u64) {
            return Err(bad(format!(
                "{count} elements run past its buffer view ({} bytes)",
                view.length()
            )));
        }
        let buffer = self.buffers.get(view.buffer().index()).map_or(0, Vec::len) as u64;
        if (view.offset() as u64).saturating_add(view.length() as u64) > buffer {
            return Err(bad(format!(
                "its buffer view runs past buffer {} ({buffer} bytes)",
                view.buffer().index()
            )));
        }
        Ok(())
    }
}

/// The JSON's root `extensions` object (the GLB's JSON chunk, or the
/// whole `.gltf`).
fn root_extensions(data: &[u8]) -> Option<serde_json::Value> {
    let json = if data.starts_with(b"glTF") {
        let len = u32::from_le_bytes(data.get(12..16)?.try_into().ok()?) as usize;
        data.get(20..20usize.checked_add(len)?)?
    } else {
        data
    };
    let mut v: serde_json::Value = serde_json::from_slice(json).ok()?;
    v.get_mut("extensions").map(serde_json::Value::take)
}

/// What an accessor holds, for the element type it must have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    Points,
    Joints,
    Weights,
    Indices,
    Matrices,
    /// Texture coordinates.
    Uvs,
}

impl Kind {
    /// Bytes an element takes once read, wherever it is stored smaller
    /// (u8 indices widen to u32, f32 matrices to f64), times the copies
    /// the loader and the renderer keep of it (a vertex's place: read,
    /// posed at rest, uploaded with its normal and colours).
    fn allocated(self) -> u64 {
        match self {
            Kind::Points => 3 * 12 + 88,
            Kind::Joints => 2 * 8,
            Kind::Weights => 2 * 16,
            Kind::Indices => 3 * 4,
            Kind::Matrices => 64 + 2 * 128,
            Kind::Uvs => 8 + 16,
        }
    }
}

/// What a figure's accessors allocate, counted each time one is read (an
/// accessor shared by 17 primitives is read 17 times), and its vertices
/// and triangles in all.
#[derive(Debug, Default)]
pub(super) struct Budget {
    bytes: u64,
    vertices: u64,
    triangles: u64,
}

impl Budget {
    /// Count `count` elements of `kind`; why not, past a bound.
    fn add(&mut self, kind: Kind, count: u64) -> Option<String> {
        self.bytes = self
            .bytes
            .saturating_add(count.saturating_mul(kind.allocated()));
        match kind {
            Kind::Points => self.vertices = self.vertices.saturating_add(count),
            Kind::Indices => self.triangles = self.triangles.saturating_add(count / 3),
            _ => {}
        }
        if self.vertices > MAX_VERTICES {
            Some(format!(
                "the figure would have over {MAX_VERTICES} vertices (a figure on the table has tens of thousands)"
            ))
        } else if self.triangles > MAX_TRIANGLES {
            Some(format!(
                "the figure would have over {MAX_TRIANGLES} triangles (a figure on the table has tens of thousands)"
            ))
        } else if self.bytes > MAX_DATA_BYTES {
            Some(format!(
                "the figure's data would need over {MAX_DATA_BYTES} bytes"
            ))
        } else {
            None
        }
    }
}

/// Refuse what the glTF reader would trip on before it says what is
/// wrong: a GLB header whose length is under its own 12 bytes (it would
/// underflow in the reader's arithmetic) and a primitive's POSITION naming
/// an accessor that is not there (its own validation indexes it before
/// checking).
fn refuse_what_the_reader_would_trip_on(path: &Path, data: &[u8]) -> Result<(), GltfError> {
    if let Some(len) = data
        .strip_prefix(b"glTF")
        .and_then(|rest| rest.get(4..8))
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .filter(|&len| len < 12)
    {
        return Err(GltfError::NotGltf {
            path: path.to_owned(),
            why: format!(
                "its GLB header gives a length of {len} bytes, less than the header's own 12"
            ),
        });
    }
    let not = |why: String| GltfError::NotGltf {
        path: path.to_owned(),
        why,
    };
    let unchecked =
        gltf::Gltf::from_slice_without_validation(data).map_err(|e| not(e.to_string()))?;
    let root = unchecked.document.as_json();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for p in &mesh.primitives {
            let pos = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(a) = p.attributes.get(&pos) {
                if a.value() >= root.accessors.len() {
                    return Err(not(format!(
                        "mesh {m}: POSITION names accessor {}, of {}",
                        a.value(),
                        root.accessors.len()
                    )));
                }
            }
        }
    }
    Ok(())
}

/// The bytes of buffer `b` of `gltf` (read from `path`): the GLB's binary
/// chunk, a base64 data URI, or a file beside the glTF (bounded in size),
/// holding at least the length the file declares.
fn buffer_data(path: &Path, gltf: &gltf::Gltf, b: &gltf::Buffer<'_>) -> Result<Vec<u8>, GltfError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let why = |why: String| GltfError::Buffer {
        path: path.to_owned(),
        why: format!("buffer {}: {why}", b.index()),
    };
    let data = match b.source() {
        gltf::buffer::Source::Bin => gltf
            .blob
            .clone()
            .ok_or_else(|| why("the GLB has no binary chunk".to_owned()))?,
        gltf::buffer::Source::Uri(uri) => {
            if let Some(rest) = uri.strip_prefix("data:") {
                let (_, b64) = rest
                    .split_once(";base64,")
                    .ok_or_else(|| why("a data URI that is not base64".to_owned()))?;
                base64(b64).ok_or_else(|| why("bad base64 in its data URI".to_owned()))?
            } else {
                let rel = inside(uri).ok_or_else(|| {
                    why(format!(
                        "{} is not a file beside the glTF (no folders above it, no absolute paths or URLs)",
                        crate::reading::quote(uri)
                    ))
                })?;
                let file = dir.join(rel);
                crate::reading::read_inside(&file, dir, MAX_FILE_BYTES).map_err(|e| match e {
                    ReadError::Io(e) if e.kind() == std::io::ErrorKind::NotFound => {
                        why(format!("missing buffer {}: {e}", file.display()))
                    }
                    ReadError::TooLarge { said, .. } => why(format!(
                        "{} is {said} bytes, over {MAX_FILE_BYTES}",
                        file.display()
                    )),
                    e => why(format!("cannot read {}: {e}", file.display())),
                })?
            }
        }
    };
    if data.len() < b.length() {
        return Err(why(format!(
            "holds {} bytes of the {} the file declares (truncated?)",
            data.len(),
            b.length()
        )));
    }
    Ok(data)
}

/// A relative path with no folder above its start, no root, no scheme.
pub(super) fn inside(uri: &str) -> Option<PathBuf> {
    if uri.contains("://") || uri.contains('\\') {
        return None;
    }
    let decoded = uri.replace("%20", " ");
    let p = Path::new(&decoded);
    p.components()
        .all(|c| matches!(c, Component::Normal(_) | Component::CurDir))
        .then(|| p.to_owned())
}

/// Standard base64 (padding optional); `None` on any other character.
pub(super) fn base64(s: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => u32::from(c - b'A'),
            b'a'..=b'z' => u32::from(c - b'a') + 26,
            b'0'..=b'9' => u32::from(c - b'0') + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        })
    };
    let s = s.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(s.len() * 3 / 4);
    for chunk in s.chunks(4) {
        let mut acc = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            acc |= value(c)? << (18 - 6 * i);
        }
        let bytes = acc.to_be_bytes();
        match chunk.len() {
            4 => out.extend_from_slice(&bytes[1..4]),
            3 => out.extend_from_slice(&bytes[1..3]),
            2 => out.push(bytes[1]),
            _ => return None,
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_reads_padded_and_unpadded_text() {
        assert_eq!(base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(base64("aGk=").unwrap(), b"hi");
        assert!(base64("a$==").is_none());
    }

    #[test]
    fn buffer_files_stay_beside_the_gltf() {
        assert!(inside("body.bin").is_some());
        assert!(inside("data/body.bin").is_some());
        for bad in ["../body.bin", "/etc/passwd", "http://x/y.bin", "a/../../b"] {
            assert!(inside(bad).is_none(), "{bad}");
        }
    }
}
