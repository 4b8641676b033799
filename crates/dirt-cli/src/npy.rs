//! The `.npy` files of the command line.
//!
//! | file        | dtype     | shape    | row                                          |
//! |-------------|-----------|----------|----------------------------------------------|
//! | `RAYS.npy`  | `float32` | `(N, 8)` | `ox oy oz tmin dx dy dz tmax`                |
//! | `HITS.npy`  | `uint32`  | `(N, 4)` | `prim, bits(t), bits(u), bits(v)`            |
//! | `TRIS.npy`  | `float32` | `(T, 9)` | `v0 v1 v2`, world space, flattened order     |
//!
//! All arrays are C order (row-major). A miss is written as [`Hit::MISS`]:
//! `prim = 0xFFFFFFFF`, `t = +inf`, `u = v = 0`. Rays are validated when read
//! ([`Ray::validate`]); the first bad row is reported by its 0-based index.

use std::fs::File;
use std::io::{self, BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

use dirt_math::{Hit, Ray, RayProblem, Triangle};
use npyz::{DType, NpyFile, NpyHeader, Order, TypeChar, WriteOptions, WriterBuilder};

/// Floats per row of a rays file.
pub const RAY_COLUMNS: u64 = 8;
/// Words per row of a hits file.
pub const HIT_COLUMNS: u64 = 4;
/// Floats per row of a triangles file.
pub const TRIANGLE_COLUMNS: u64 = 9;

/// What can go wrong reading or writing the `.npy` files of the command line.
#[derive(Debug, thiserror::Error)]
pub enum NpyError {
    #[error("cannot open {}", path.display())]
    Open {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    #[error("{}: not a .npy file ({reason})", path.display())]
    NotNpy { path: PathBuf, reason: String },
    #[error("{}: dtype is {found}, expected float32 ('<f4'); convert with array.astype(numpy.float32)", path.display())]
    DType { path: PathBuf, found: String },
    #[error("{}: shape is {}, expected (N, {columns})", path.display(), shape_text(found))]
    Shape {
        path: PathBuf,
        found: Vec<u64>,
        columns: u64,
    },
    #[error(
        "{}: array is stored in Fortran order; save it in C order (numpy.ascontiguousarray) before numpy.save",
        path.display()
    )]
    FortranOrder { path: PathBuf },
    #[error("{}: cannot read the data after the header ({reason}); is the file truncated?", path.display())]
    Data { path: PathBuf, reason: String },
    #[error("{}: row {row}: {problem} (ray: {})", path.display(), row_text(values))]
    BadRay {
        path: PathBuf,
        row: usize,
        problem: RayProblem,
        values: [f32; 8],
    },
    #[error("cannot write {}", path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
}

impl NpyError {
    /// The 0-based row a [`NpyError::BadRay`] is about.
    #[cfg(test)]
    pub fn row(&self) -> Option<usize> {
        match self {
            NpyError::BadRay { row, .. } => Some(*row),
            _ => None,
        }
    }
}

fn shape_text(shape: &[u64]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => {
            let parts: Vec<String> = shape.iter().map(u64::to_string).collect();
            format!("({})", parts.join(", "))
        }
    }
}

fn row_text(v: &[f32; 8]) -> String {
    format!(
        "origin=({}, {}, {}) tmin={} dir=({}, {}, {}) tmax={}",
        v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]
    )
}

/// The ray of one row `ox oy oz tmin dx dy dz tmax`.
pub fn ray_from_row(r: &[f32; 8]) -> Ray {
    Ray {
        origin: [r[0], r[1], r[2]],
        tmin: r[3],
        dir: [r[4], r[5], r[6]],
        tmax: r[7],
    }
}

/// The row `ox oy oz tmin dx dy dz tmax` of a ray.
pub fn row_from_ray(r: &Ray) -> [f32; 8] {
    [
        r.origin[0],
        r.origin[1],
        r.origin[2],
        r.tmin,
        r.dir[0],
        r.dir[1],
        r.dir[2],
        r.tmax,
    ]
}

/// Reads and validates a rays file.
pub fn read_rays(path: &Path) -> Result<Vec<Ray>, NpyError> {
    let file = File::open(path).map_err(|source| NpyError::Open {
        path: path.to_owned(),
        source,
    })?;
    read_rays_from(BufReader::new(file), path)
}

/// Reads and validates rays from `reader`; `path` only names the source in errors.
pub fn read_rays_from(reader: impl Read, path: &Path) -> Result<Vec<Ray>, NpyError> {
    let data = read_f32_matrix(reader, path, RAY_COLUMNS)?;
    let mut rays = Vec::with_capacity(data.len() / RAY_COLUMNS as usize);
    for (row, chunk) in data.chunks_exact(RAY_COLUMNS as usize).enumerate() {
        let mut values = [0.0f32; 8];
        values.copy_from_slice(chunk);
        let ray = ray_from_row(&values);
        ray.validate().map_err(|problem| NpyError::BadRay {
            path: path.to_owned(),
            row,
            problem,
            values,
        })?;
        rays.push(ray);
    }
    Ok(rays)
}

/// Reads a hits file (`dirt eval` compares the hits of whole `dirt trace` runs).
pub fn read_hits(path: &Path) -> Result<Vec<Hit>, NpyError> {
    let file = File::open(path).map_err(|source| NpyError::Open {
        path: path.to_owned(),
        source,
    })?;
    let data: Vec<u32> = read_matrix(BufReader::new(file), path, HIT_COLUMNS, TypeChar::Uint)?;
    Ok(data
        .chunks_exact(HIT_COLUMNS as usize)
        .map(|w| Hit {
            prim: w[0],
            t: f32::from_bits(w[1]),
            u: f32::from_bits(w[2]),
            v: f32::from_bits(w[3]),
        })
        .collect())
}

/// Reads a triangles file (used by the tests to read back `dirt triangles`).
#[cfg(test)]
pub fn read_triangles_from(reader: impl Read, path: &Path) -> Result<Vec<Triangle>, NpyError> {
    let data = read_f32_matrix(reader, path, TRIANGLE_COLUMNS)?;
    Ok(data
        .chunks_exact(TRIANGLE_COLUMNS as usize)
        .map(|c| Triangle {
            v: [[c[0], c[1], c[2]], [c[3], c[4], c[5]], [c[6], c[7], c[8]]],
        })
        .collect())
}

/// Reads a C-order float32 array of shape `(N, columns)` as a flat vector.
fn read_f32_matrix(reader: impl Read, path: &Path, columns: u64) -> Result<Vec<f32>, NpyError> {
    read_matrix(reader, path, columns, TypeChar::Float)
}

/// Reads a C-order array of 4-byte `kind` values (`f32`, `u32`) of shape
/// `(N, columns)` as a flat vector.
fn read_matrix<T: npyz::Deserialize>(
    mut reader: impl Read,
    path: &Path,
    columns: u64,
    kind: TypeChar,
) -> Result<Vec<T>, NpyError> {
    let header = read_header(&mut reader, path)?;
    let npy = NpyFile::with_header(header, reader);
    let dtype = npy.dtype();
    let is_kind =
        matches!(&dtype, DType::Plain(ts) if ts.type_char() == kind && ts.size_field() == 4);
    if !is_kind {
        return Err(NpyError::DType {
            path: path.to_owned(),
            found: dtype_text(&dtype),
        });
    }
    let shape = npy.shape().to_vec();
    if shape.len() != 2 || shape[1] != columns {
        return Err(NpyError::Shape {
            path: path.to_owned(),
            found: shape,
            columns,
        });
    }
    if npy.order() == Order::Fortran {
        return Err(NpyError::FortranOrder {
            path: path.to_owned(),
        });
    }
    let data_err = |reason: String| NpyError::Data {
        path: path.to_owned(),
        reason,
    };
    let expected = shape[0]
        .checked_mul(columns)
        .and_then(|n| usize::try_from(n).ok())
        .ok_or_else(|| data_err(format!("{} rows is too many", shape[0])))?;
    let reader = npy.data::<T>().map_err(|e| data_err(e.to_string()))?;
    // Do not trust the header's row count for the allocation: grow as data arrives.
    let mut out = Vec::with_capacity(expected.min(1 << 24));
    for value in reader {
        out.push(value.map_err(|e| data_err(e.to_string()))?);
    }
    if out.len() != expected {
        return Err(data_err(format!(
            "expected {expected} values, found {}",
            out.len()
        )));
    }
    Ok(out)
}

/// Longest header accepted (numpy itself refuses more than 10 000 bytes by default).
const MAX_HEADER_BYTES: usize = 1 << 20;

/// Reads the header: magic, version, length and the dictionary, which is
/// checked for a shape whose element count overflows before npyz sees it
/// (npyz multiplies the dimensions unchecked and panics on overflow).
fn read_header(reader: &mut impl Read, path: &Path) -> Result<NpyHeader, NpyError> {
    let not_npy = |reason: String| NpyError::NotNpy {
        path: path.to_owned(),
        reason,
    };
    let mut prefix = vec![0u8; 8];
    reader
        .read_exact(&mut prefix)
        .map_err(|_| not_npy("shorter than the 8-byte .npy preamble".into()))?;
    if &prefix[..6] != b"\x93NUMPY" {
        return Err(not_npy(
            "it does not start with the .npy magic \\x93NUMPY".into(),
        ));
    }
    let len_bytes = match prefix[6] {
        1 => 2,
        2 | 3 => 4,
        v => return Err(not_npy(format!("unsupported .npy format version {v}"))),
    };
    let mut len = vec![0u8; len_bytes];
    reader
        .read_exact(&mut len)
        .map_err(|_| not_npy("the header length is cut off".into()))?;
    let header_len = len
        .iter()
        .rev()
        .fold(0usize, |acc, &b| (acc << 8) | b as usize);
    if header_len > MAX_HEADER_BYTES {
        return Err(not_npy(format!(
            "header of {header_len} bytes (at most {MAX_HEADER_BYTES} accepted)"
        )));
    }
    prefix.extend(len);
    let start = prefix.len();
    prefix.resize(start + header_len, 0);
    reader
        .read_exact(&mut prefix[start..])
        .map_err(|_| not_npy("the header is cut off".into()))?;
    // npyz's parser of the dictionary takes time exponential in the nesting
    // of brackets (found by fuzzing: 100 nested braces ran for minutes). A
    // valid header is one dictionary; structured dtypes nest a few levels.
    let depth = nesting_depth(&prefix[start..]);
    if depth > MAX_HEADER_NESTING {
        return Err(not_npy(format!(
            "the header dictionary nests brackets {depth} deep (at most {MAX_HEADER_NESTING})"
        )));
    }
    if let Some(dims) = shape_in(&prefix[start..])
        && dims
            .iter()
            .filter(|&&d| d != 0)
            .try_fold(1u64, |acc, &d| acc.checked_mul(d))
            .is_none()
    {
        return Err(not_npy(format!(
            "shape {} has more elements than a 64-bit count holds",
            shape_text(&dims)
        )));
    }
    NpyHeader::from_reader(&prefix[..]).map_err(|e| not_npy(e.to_string()))
}

/// Deepest header nesting accepted: `{[(('name', '<f4'), (2,))]}` is 4.
const MAX_HEADER_NESTING: usize = 6;

/// Deepest nesting of `{`, `[` and `(` in `dict` (quotes are not special:
/// counting brackets inside names only makes the check stricter).
fn nesting_depth(dict: &[u8]) -> usize {
    let (mut depth, mut max) = (0usize, 0usize);
    for &c in dict {
        match c {
            b'{' | b'[' | b'(' => {
                depth += 1;
                max = max.max(depth);
            }
            b'}' | b']' | b')' => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    max
}

/// The dimensions of the `'shape'` tuple of a header dictionary, when it is
/// plain enough to read (npyz validates the rest).
fn shape_in(dict: &[u8]) -> Option<Vec<u64>> {
    let text = std::str::from_utf8(dict).ok()?;
    let after = &text[text.find("shape")? + "shape".len()..];
    let open = after.find('(')?;
    let close = after[open..].find(')')? + open;
    after[open + 1..close]
        .split(',')
        .map(|d| d.trim().trim_end_matches('L'))
        .filter(|d| !d.is_empty())
        .map(|d| d.parse::<u64>().ok())
        .collect()
}

fn dtype_text(dtype: &DType) -> String {
    match dtype {
        DType::Plain(ts) => {
            let name = match (ts.type_char(), ts.size_field()) {
                (TypeChar::Float, n) => format!("float{}", n * 8),
                (TypeChar::Int, n) => format!("int{}", n * 8),
                (TypeChar::Uint, n) => format!("uint{}", n * 8),
                (TypeChar::Bool, _) => "bool".to_owned(),
                _ => return format!("'{ts}'"),
            };
            format!("{name} ('{ts}')")
        }
        other => format!("a structured dtype {}", other.descr()),
    }
}

/// Writes rays as float32 `(N, 8)`.
pub fn write_rays(path: &Path, rays: &[Ray]) -> Result<(), NpyError> {
    write_file(path, |w| write_rays_to(w, rays))
}

/// Writes closest hits as uint32 `(N, 4)`; any miss is written as [`Hit::MISS`].
pub fn write_hits(path: &Path, hits: &[Hit]) -> Result<(), NpyError> {
    write_file(path, |w| write_hits_to(w, hits))
}

/// Writes triangles as float32 `(T, 9)`.
pub fn write_triangles(path: &Path, tris: &[Triangle]) -> Result<(), NpyError> {
    write_file(path, |w| write_triangles_to(w, tris))
}

fn write_file(
    path: &Path,
    body: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> Result<(), NpyError> {
    let write_err = |source| NpyError::Write {
        path: path.to_owned(),
        source,
    };
    let file = File::create(path).map_err(write_err)?;
    let mut w = BufWriter::new(file);
    body(&mut w).map_err(write_err)?;
    w.flush().map_err(write_err)
}

pub fn write_rays_to(w: impl Write, rays: &[Ray]) -> io::Result<()> {
    write_matrix::<f32>(
        w,
        RAY_COLUMNS,
        rays.len(),
        rays.iter().flat_map(row_from_ray),
    )
}

pub fn write_hits_to(w: impl Write, hits: &[Hit]) -> io::Result<()> {
    let words = hits.iter().flat_map(|h| {
        if h.is_hit() {
            h.bits()
        } else {
            Hit::MISS.bits()
        }
    });
    write_matrix::<u32>(w, HIT_COLUMNS, hits.len(), words)
}

pub fn write_triangles_to(w: impl Write, tris: &[Triangle]) -> io::Result<()> {
    write_matrix::<f32>(
        w,
        TRIANGLE_COLUMNS,
        tris.len(),
        tris.iter().flat_map(|t| t.v.into_iter().flatten()),
    )
}

fn write_matrix<T: npyz::AutoSerialize>(
    w: impl Write,
    columns: u64,
    rows: usize,
    values: impl IntoIterator<Item = T>,
) -> io::Result<()> {
    let mut writer = WriteOptions::<T>::new()
        .default_dtype()
        .shape(&[rows as u64, columns])
        .writer(w)
        .begin_nd()?;
    writer.extend(values)?;
    writer.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    fn name() -> &'static Path {
        Path::new("test.npy")
    }

    fn good_rays() -> Vec<Ray> {
        vec![
            Ray {
                origin: [0.0, 1.0, 2.0],
                tmin: 0.0,
                dir: [0.0, 0.0, 1.0],
                tmax: f32::INFINITY,
            },
            Ray {
                origin: [-3.5, 1e-30, 7.0],
                tmin: 0.25,
                dir: [1.0, -2.0, 0.5],
                tmax: 10.0,
            },
            Ray {
                origin: [1.0, 1.0, 1.0],
                tmin: 1.0,
                dir: [0.0, -1e-20, 0.0],
                tmax: 1.0,
            },
        ]
    }

    /// An `.npy` file (format 1.0) with any dtype, shape and order, written by
    /// hand so the tests do not depend on what the writer is willing to produce.
    fn raw_npy(descr: &str, shape: &[u64], fortran: bool, data: &[u8]) -> Vec<u8> {
        let shape_text = match shape {
            [n] => format!("({n},)"),
            _ => format!(
                "({})",
                shape
                    .iter()
                    .map(u64::to_string)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        let order = if fortran { "True" } else { "False" };
        let mut dict =
            format!("{{'descr': '{descr}', 'fortran_order': {order}, 'shape': {shape_text}, }}");
        while (10 + dict.len() + 1) % 64 != 0 {
            dict.push(' ');
        }
        dict.push('\n');
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend_from_slice(
            &u16::try_from(dict.len())
                .expect("short header")
                .to_le_bytes(),
        );
        out.extend_from_slice(dict.as_bytes());
        out.extend_from_slice(data);
        out
    }

    fn f32_bytes(values: &[f32], big_endian: bool) -> Vec<u8> {
        values
            .iter()
            .flat_map(|v| {
                if big_endian {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                }
            })
            .collect()
    }

    fn f32_file(rows: &[[f32; 8]]) -> Vec<u8> {
        let mut out = Vec::new();
        write_matrix::<f32>(&mut out, 8, rows.len(), rows.iter().flatten().copied())
            .expect("write");
        out
    }

    fn read(bytes: &[u8]) -> Result<Vec<Ray>, NpyError> {
        read_rays_from(bytes, name())
    }

    #[test]
    fn rays_round_trip_bit_exactly() {
        let rays = good_rays();
        let mut bytes = Vec::new();
        write_rays_to(&mut bytes, &rays).expect("write");
        let back = read(&bytes).expect("read");
        assert_eq!(back.len(), rays.len());
        for (a, b) in rays.iter().zip(&back) {
            assert_eq!(bytemuck::bytes_of(a), bytemuck::bytes_of(b));
        }
    }

    #[test]
    fn header_says_float32_c_order_n_by_8() {
        let mut bytes = Vec::new();
        write_rays_to(&mut bytes, &good_rays()).expect("write");
        let npy = NpyFile::new(&bytes[..]).expect("header");
        assert_eq!(npy.shape(), &[3, 8]);
        assert_eq!(npy.order(), Order::C);
        assert_eq!(npy.dtype().descr(), "'<f4'");
    }

    #[test]
    fn empty_rays_file_is_fine() {
        let mut bytes = Vec::new();
        write_rays_to(&mut bytes, &[]).expect("write");
        assert!(read(&bytes).expect("read").is_empty());
    }

    #[test]
    fn hits_are_written_as_u32_words() {
        let hits = [
            Hit {
                prim: 7,
                t: 1.5,
                u: 0.25,
                v: 0.5,
            },
            Hit::MISS,
            // A miss with stray fields is normalised to Hit::MISS.
            Hit {
                prim: dirt_math::INVALID_ID,
                t: 3.0,
                u: 1.0,
                v: 1.0,
            },
        ];
        let mut bytes = Vec::new();
        write_hits_to(&mut bytes, &hits).expect("write");
        let npy = NpyFile::new(&bytes[..]).expect("header");
        assert_eq!(npy.shape(), &[3, 4]);
        assert_eq!(npy.dtype().descr(), "'<u4'");
        let words: Vec<u32> = npy.into_vec().expect("data");
        assert_eq!(&words[0..4], &hits[0].bits());
        assert_eq!(&words[4..8], &[u32::MAX, f32::INFINITY.to_bits(), 0, 0]);
        assert_eq!(&words[8..12], &Hit::MISS.bits());
    }

    #[test]
    fn triangles_round_trip() {
        let tris = vec![
            Triangle {
                v: [[0.0, 1.0, 2.0], [3.0, 4.0, 5.0], [6.0, 7.0, 8.0]],
            },
            Triangle {
                v: [[-1.0, 0.5, 1e-7], [9.0, 9.5, 10.0], [-0.0, 2.0, 3.0]],
            },
        ];
        let mut bytes = Vec::new();
        write_triangles_to(&mut bytes, &tris).expect("write");
        let npy = NpyFile::new(&bytes[..]).expect("header");
        assert_eq!(npy.shape(), &[2, 9]);
        let flat: Vec<f32> = npy.into_vec().expect("data");
        assert_eq!(flat[3..6], [3.0, 4.0, 5.0]);
        let back = read_triangles_from(&bytes[..], name()).expect("read");
        assert_eq!(back, tris);
    }

    #[test]
    fn not_an_npy_file() {
        let err = read(b"ox oy oz tmin dx dy dz tmax\n0 0 0 0 0 0 1 1\n").expect_err("text");
        assert!(matches!(err, NpyError::NotNpy { .. }), "{err}");
        assert!(err.to_string().contains("not a .npy file"), "{err}");
        let err = read(b"").expect_err("empty");
        assert!(matches!(err, NpyError::NotNpy { .. }), "{err}");
    }

    #[test]
    fn wrong_dtype() {
        for (dtype, word) in [
            ("<f8", "float64"),
            ("<i4", "int32"),
            ("<u4", "uint32"),
            ("<f2", "float16"),
        ] {
            let err = read(&raw_npy(dtype, &[2, 8], false, &[0u8; 16 * 8])).expect_err(dtype);
            assert!(matches!(err, NpyError::DType { .. }), "{dtype}: {err}");
            assert!(err.to_string().contains(word), "{err}");
            assert!(err.to_string().contains("expected float32"), "{err}");
        }
    }

    #[test]
    fn big_endian_float32_is_accepted() {
        let row = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 2.0];
        let rays =
            read(&raw_npy(">f4", &[1, 8], false, &f32_bytes(&row, true))).expect("big endian");
        assert_eq!(rays[0].dir, [0.0, 0.0, 1.0]);
        assert_eq!(rays[0].tmax, 2.0);
    }

    #[test]
    fn wrong_shape() {
        for shape in [vec![3, 7], vec![24], vec![3, 8, 1], vec![8, 3], vec![]] {
            let n: u64 = shape.iter().product();
            let err = read(&raw_npy(
                "<f4",
                &shape,
                false,
                &f32_bytes(&vec![1.0; n as usize], false),
            ))
            .expect_err("shape");
            match &err {
                NpyError::Shape { found, columns, .. } => {
                    assert_eq!(found, &shape);
                    assert_eq!(*columns, 8);
                }
                other => panic!("{shape:?}: {other}"),
            }
            assert!(err.to_string().contains("expected (N, 8)"), "{err}");
        }
        let err =
            read(&raw_npy("<f4", &[24], false, &f32_bytes(&[1.0; 24], false))).expect_err("1-D");
        assert!(err.to_string().contains("shape is (24,)"), "{err}");
    }

    #[test]
    fn fortran_order_is_refused_with_a_hint() {
        let err = read(&raw_npy(
            "<f4",
            &[2, 8],
            true,
            &f32_bytes(&[1.0; 16], false),
        ))
        .expect_err("fortran");
        assert!(matches!(err, NpyError::FortranOrder { .. }), "{err}");
        assert!(err.to_string().contains("C order"), "{err}");
    }

    /// Found by the `random_headers_into_the_rays_reader` property test:
    /// npyz multiplied the dimensions unchecked and panicked.
    #[test]
    fn shape_overflowing_64_bits_is_refused() {
        for shape in [[5u64, u64::MAX / 4], [0, 1 << 40]] {
            let bytes = raw_npy("<f4", &shape, false, &[]);
            let e = read(&bytes).expect_err("refused");
            assert!(
                matches!(e, NpyError::NotNpy { .. } | NpyError::Shape { .. }),
                "{e}"
            );
        }
        let bytes = raw_npy("<f4", &[1 << 40, 1 << 40, 8], false, &[]);
        let e = read(&bytes).expect_err("refused").to_string();
        assert!(e.contains("more elements than a 64-bit count holds"), "{e}");
    }

    /// Found by `cargo fuzz run npy_rays` (a timeout): npyz's header parser
    /// ran for minutes on 98 nested braces. This rebuilds that input.
    #[test]
    fn deeply_nested_header_is_refused_at_once() {
        let mut dict = "{".repeat(98).into_bytes();
        dict.extend_from_slice(b"'descr': '>f4', 'fortran_order': False,              2");
        dict.resize(0xd5 - 12, b' ');
        dict.push(b'\n');
        let mut bytes = b"\x93NUMPY\x02\x00".to_vec();
        bytes.extend_from_slice(&(dict.len() as u32).to_le_bytes());
        bytes.extend_from_slice(&dict);
        bytes.extend_from_slice(&[
            0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xbf, 0x80, 0, 0, 0x7f, 0x80, 0, 0,
        ]);
        let e = read(&bytes).expect_err("refused").to_string();
        assert!(e.contains("nests brackets 98 deep"), "{e}");
        // A structured dtype's usual nesting still reaches the dtype check.
        let bytes = raw_npy("[('x', '<f4', (8,))]", &[1], false, &[0; 32]);
        assert!(
            !read(&bytes)
                .expect_err("structured")
                .to_string()
                .contains("nests")
        );
    }

    #[test]
    fn truncated_data() {
        let mut bytes = f32_file(&[[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0]; 4]);
        bytes.truncate(bytes.len() - 6);
        let err = read(&bytes).expect_err("truncated");
        assert!(matches!(err, NpyError::Data { .. }), "{err}");
    }

    /// Each malformed ray, placed at row 2 after two good rows, with the problem it must report.
    #[test]
    fn bad_rays_name_the_problem_and_the_row() {
        let good = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 5.0];
        let nan = f32::NAN;
        let inf = f32::INFINITY;
        let cases: [([f32; 8], RayProblem, &str); 10] = [
            (
                [nan, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 5.0],
                RayProblem::NonFiniteOrigin,
                "origin is not finite",
            ),
            (
                [0.0, inf, 0.0, 0.0, 0.0, 0.0, 1.0, 5.0],
                RayProblem::NonFiniteOrigin,
                "origin is not finite",
            ),
            (
                [0.0, 0.0, 0.0, 0.0, 0.0, -inf, 1.0, 5.0],
                RayProblem::NonFiniteDirection,
                "direction is not finite",
            ),
            (
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, nan, 5.0],
                RayProblem::NonFiniteDirection,
                "direction is not finite",
            ),
            (
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 5.0],
                RayProblem::ZeroDirection,
                "direction is zero",
            ),
            (
                [0.0, 0.0, 0.0, 0.0, -0.0, 0.0, 0.0, 5.0],
                RayProblem::ZeroDirection,
                "direction is zero",
            ),
            (
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, nan],
                RayProblem::NanRange,
                "NaN",
            ),
            (
                [0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 1.0, 5.0],
                RayProblem::BadTmin,
                "tmin",
            ),
            (
                [0.0, 0.0, 0.0, inf, 0.0, 0.0, 1.0, inf],
                RayProblem::BadTmin,
                "tmin",
            ),
            (
                [0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 1.0, 1.0],
                RayProblem::EmptyRange,
                "tmax < tmin",
            ),
        ];
        for (bad, problem, words) in cases {
            let err = read(&f32_file(&[good, good, bad, good])).expect_err("bad ray");
            match &err {
                NpyError::BadRay {
                    row, problem: p, ..
                } => {
                    assert_eq!(*row, 2, "{err}");
                    assert_eq!(*p, problem, "{err}");
                }
                other => panic!("{bad:?}: {other}"),
            }
            assert_eq!(err.row(), Some(2));
            let msg = err.to_string();
            assert!(msg.contains("row 2:"), "{msg}");
            assert!(msg.contains(words), "{msg}");
            assert!(msg.starts_with("test.npy"), "{msg}");
        }
    }

    #[test]
    fn the_first_bad_row_is_reported() {
        let good = [0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 5.0];
        let zero_dir = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 5.0];
        let mut rows = vec![good; 10];
        rows[7] = zero_dir;
        rows[9] = zero_dir;
        let err = read(&f32_file(&rows)).expect_err("bad");
        assert_eq!(err.row(), Some(7), "{err}");
    }

    #[test]
    fn unbounded_and_point_rays_are_valid() {
        // tmax = +inf and tmin == tmax are legal (Ray::validate).
        let rows = [
            [0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, f32::INFINITY],
            [0.0, 0.0, 0.0, 3.0, 1.0, 0.0, 0.0, 3.0],
        ];
        assert_eq!(read(&f32_file(&rows)).expect("valid").len(), 2);
    }
}
