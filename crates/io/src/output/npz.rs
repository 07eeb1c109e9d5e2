//! NumPy `.npz` archives: a ZIP file (entries stored, not compressed) of `.npy` arrays, as
//! `numpy.savez` writes them and `numpy.load` reads them, written by hand (format 1.0 of
//! `.npy`, little-endian, C order; plain ZIP without ZIP64, so below 4 GiB and 65 535 arrays).

use std::path::Path;

use crate::OutputError;
use crate::atomic::write_atomic_bytes;

/// The values of one array, flat in C (row-major) order.
#[derive(Clone, Debug, PartialEq)]
pub enum NpyData {
    /// `float64` (`<f8`).
    F64(Vec<f64>),
    /// `int64` (`<i8`).
    I64(Vec<i64>),
    /// `bool` (`|b1`).
    Bool(Vec<bool>),
    /// Unicode strings (`<U{n}`, n the longest in characters), for labels.
    Str(Vec<String>),
}

impl NpyData {
    fn len(&self) -> usize {
        match self {
            NpyData::F64(v) => v.len(),
            NpyData::I64(v) => v.len(),
            NpyData::Bool(v) => v.len(),
            NpyData::Str(v) => v.len(),
        }
    }
}

/// An n-dimensional array: its shape and its values in C order.
#[derive(Clone, Debug, PartialEq)]
pub struct NpyArray {
    /// The shape (`[]` for a scalar, `[n]`, `[n, 3]`, …).
    pub shape: Vec<usize>,
    /// The values; their count is the product of `shape`.
    pub data: NpyData,
}

impl NpyArray {
    /// A 1-D array of doubles.
    pub fn f64(values: Vec<f64>) -> Self {
        Self {
            shape: vec![values.len()],
            data: NpyData::F64(values),
        }
    }

    /// A 0-D array (a scalar) of a double.
    pub fn scalar(value: f64) -> Self {
        Self {
            shape: Vec::new(),
            data: NpyData::F64(vec![value]),
        }
    }

    /// An `(n, 3)` array of doubles.
    pub fn vec3(rows: &[[f64; 3]]) -> Self {
        Self {
            shape: vec![rows.len(), 3],
            data: NpyData::F64(rows.iter().flatten().copied().collect()),
        }
    }

    /// A 1-D array of integers.
    pub fn i64(values: Vec<i64>) -> Self {
        Self {
            shape: vec![values.len()],
            data: NpyData::I64(values),
        }
    }

    /// A 1-D array of booleans.
    pub fn bool(values: Vec<bool>) -> Self {
        Self {
            shape: vec![values.len()],
            data: NpyData::Bool(values),
        }
    }

    /// A 1-D array of strings.
    pub fn strings(values: Vec<String>) -> Self {
        Self {
            shape: vec![values.len()],
            data: NpyData::Str(values),
        }
    }

    /// A 0-D array of one string.
    pub fn string(value: &str) -> Self {
        Self {
            shape: Vec::new(),
            data: NpyData::Str(vec![value.to_string()]),
        }
    }

    /// The array with another shape of the same size (`None` when the sizes differ).
    pub fn reshaped(self, shape: Vec<usize>) -> Option<Self> {
        (shape.iter().product::<usize>() == self.data.len()).then_some(Self {
            shape,
            data: self.data,
        })
    }

    /// The `.npy` bytes: magic, version 1.0, the header dictionary padded to a multiple of 64
    /// bytes, then the data. Fails when the shape does not match the number of values.
    pub fn to_npy(&self) -> Result<Vec<u8>, String> {
        let count: usize = self.shape.iter().product();
        if count != self.data.len() {
            return Err(format!(
                "shape {:?} holds {count} values, but {} are given",
                self.shape,
                self.data.len()
            ));
        }
        let width = match &self.data {
            NpyData::Str(v) => v
                .iter()
                .map(|s| s.chars().count())
                .max()
                .unwrap_or(0)
                .max(1),
            _ => 0,
        };
        let descr = match &self.data {
            NpyData::F64(_) => "<f8".to_string(),
            NpyData::I64(_) => "<i8".to_string(),
            NpyData::Bool(_) => "|b1".to_string(),
            NpyData::Str(_) => format!("<U{width}"),
        };
        let shape = match self.shape.as_slice() {
            [] => "()".to_string(),
            [n] => format!("({n},)"),
            dims => format!(
                "({})",
                dims.iter()
                    .map(usize::to_string)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        let mut header =
            format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
        // magic (6) + version (2) + header length (2) + header + '\n' ≡ 0 (mod 64).
        let unpadded = 10 + header.len() + 1;
        header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
        header.push('\n');
        let header_len = u16::try_from(header.len()).map_err(|_| "header too long")?;
        let mut out = Vec::with_capacity(10 + header.len() + 8 * count);
        out.extend_from_slice(b"\x93NUMPY\x01\x00");
        out.extend_from_slice(&header_len.to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        match &self.data {
            NpyData::F64(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            NpyData::I64(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            NpyData::Bool(v) => out.extend(v.iter().map(|&b| u8::from(b))),
            NpyData::Str(v) => {
                for s in v {
                    let n = s.chars().count();
                    for c in s.chars() {
                        out.extend_from_slice(&u32::from(c).to_le_bytes());
                    }
                    out.extend(std::iter::repeat_n(0u8, 4 * (width - n)));
                }
            }
        }
        Ok(out)
    }
}

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320), as ZIP requires.
pub fn crc32(bytes: &[u8]) -> u32 {
    const TABLE: [u32; 256] = {
        let mut table = [0u32; 256];
        let mut n = 0;
        while n < 256 {
            let mut c = n as u32;
            let mut k = 0;
            while k < 8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
                k += 1;
            }
            table[n] = c;
            n += 1;
        }
        table
    };
    let mut c = 0xFFFF_FFFFu32;
    for &b in bytes {
        c = TABLE[((c ^ u32::from(b)) & 0xFF) as usize] ^ (c >> 8);
    }
    c ^ 0xFFFF_FFFF
}

/// The bytes of an `.npz` archive of `arrays` (each stored as `{name}.npy`).
pub fn npz_bytes(arrays: &[(&str, NpyArray)]) -> Result<Vec<u8>, String> {
    const DOS_DATE: u16 = (1 << 5) | 1; // 1980-01-01
    let count = u16::try_from(arrays.len()).map_err(|_| "more than 65535 arrays")?;
    let too_big = || "the archive would exceed 4 GiB (ZIP64 is not written)".to_string();
    let mut out = Vec::new();
    let mut central = Vec::new();
    for (name, array) in arrays {
        let npy = array.to_npy().map_err(|e| format!("array `{name}`: {e}"))?;
        let file_name = format!("{name}.npy");
        let name_len = u16::try_from(file_name.len()).map_err(|_| "array name too long")?;
        let size = u32::try_from(npy.len()).map_err(|_| too_big())?;
        let offset = u32::try_from(out.len()).map_err(|_| too_big())?;
        let crc = crc32(&npy);
        let mut common = Vec::new();
        for v in [20u16, 0, 0, 0, DOS_DATE] {
            common.extend_from_slice(&v.to_le_bytes());
        }
        for v in [crc, size, size] {
            common.extend_from_slice(&v.to_le_bytes());
        }
        common.extend_from_slice(&name_len.to_le_bytes());
        common.extend_from_slice(&0u16.to_le_bytes()); // extra field length
        out.extend_from_slice(&0x0403_4b50u32.to_le_bytes());
        out.extend_from_slice(&common);
        out.extend_from_slice(file_name.as_bytes());
        out.extend_from_slice(&npy);
        central.extend_from_slice(&0x0201_4b50u32.to_le_bytes());
        central.extend_from_slice(&20u16.to_le_bytes()); // version made by
        central.extend_from_slice(&common);
        for v in [0u16, 0, 0] {
            // comment length, disk number, internal attributes
            central.extend_from_slice(&v.to_le_bytes());
        }
        central.extend_from_slice(&0u32.to_le_bytes()); // external attributes
        central.extend_from_slice(&offset.to_le_bytes());
        central.extend_from_slice(file_name.as_bytes());
    }
    let cd_offset = u32::try_from(out.len()).map_err(|_| too_big())?;
    let cd_size = u32::try_from(central.len()).map_err(|_| too_big())?;
    out.extend_from_slice(&central);
    out.extend_from_slice(&0x0605_4b50u32.to_le_bytes());
    for v in [0u16, 0, count, count] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&cd_size.to_le_bytes());
    out.extend_from_slice(&cd_offset.to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes());
    u32::try_from(out.len()).map_err(|_| too_big())?;
    Ok(out)
}

/// Writes `arrays` as an `.npz` archive at `path` (atomically), readable by `numpy.load`.
///
/// ```
/// use nurbspring_io::output::{NpyArray, write_npz};
/// # let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("model.npz");
/// write_npz(&path, &[
///     ("positions", NpyArray::vec3(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])),
///     ("fixed", NpyArray::bool(vec![true, false])),
/// ]).unwrap();
/// let bytes = std::fs::read(&path).unwrap();
/// assert_eq!(&bytes[..4], b"PK\x03\x04");
/// ```
pub fn write_npz(path: impl AsRef<Path>, arrays: &[(&str, NpyArray)]) -> Result<(), OutputError> {
    let path = path.as_ref();
    let bytes = npz_bytes(arrays).map_err(|m| OutputError::invalid(path, m))?;
    write_atomic_bytes(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_of_known_strings() {
        assert_eq!(crc32(b""), 0);
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(
            crc32(b"The quick brown fox jumps over the lazy dog"),
            0x414F_A339
        );
    }

    #[test]
    fn npy_header_is_aligned_and_describes_the_array() {
        let a = NpyArray::vec3(&[[1.0, 2.0, 3.0]]);
        let b = a.to_npy().unwrap();
        assert_eq!(&b[..8], b"\x93NUMPY\x01\x00");
        let len = u16::from_le_bytes([b[8], b[9]]) as usize;
        assert_eq!((10 + len) % 64, 0);
        let header = std::str::from_utf8(&b[10..10 + len]).unwrap();
        assert!(header.starts_with("{'descr': '<f8', 'fortran_order': False, 'shape': (1, 3), }"));
        assert!(header.ends_with('\n'));
        assert_eq!(b.len(), 10 + len + 24);
        assert_eq!(&b[10 + len..10 + len + 8], &1.0f64.to_le_bytes());
        let s = NpyArray::strings(vec!["ab".into(), "c".into()])
            .to_npy()
            .unwrap();
        let len = u16::from_le_bytes([s[8], s[9]]) as usize;
        assert!(
            std::str::from_utf8(&s[10..10 + len])
                .unwrap()
                .contains("'<U2'")
        );
        assert_eq!(&s[10 + len..], b"a\0\0\0b\0\0\0c\0\0\0\0\0\0\0");
        let scalar = NpyArray::scalar(0.5).to_npy().unwrap();
        assert!(String::from_utf8_lossy(&scalar).contains("'shape': ()"));
        let bad = NpyArray {
            shape: vec![2, 2],
            data: NpyData::I64(vec![1]),
        };
        assert!(bad.to_npy().is_err());
    }

    #[test]
    fn zip_directory_points_at_the_entries() {
        let bytes = npz_bytes(&[
            ("a", NpyArray::i64(vec![1, 2, 3])),
            ("b", NpyArray::bool(vec![true])),
        ])
        .unwrap();
        let eocd = bytes.len() - 22;
        assert_eq!(&bytes[eocd..eocd + 4], &0x0605_4b50u32.to_le_bytes());
        let entries = u16::from_le_bytes([bytes[eocd + 10], bytes[eocd + 11]]);
        assert_eq!(entries, 2);
        let cd_offset = u32::from_le_bytes(bytes[eocd + 16..eocd + 20].try_into().unwrap());
        assert_eq!(
            &bytes[cd_offset as usize..cd_offset as usize + 4],
            &0x0201_4b50u32.to_le_bytes()
        );
        // The first entry's name and its data's CRC.
        assert_eq!(&bytes[30..35], b"a.npy");
        let size = u32::from_le_bytes(bytes[18..22].try_into().unwrap()) as usize;
        let crc = u32::from_le_bytes(bytes[14..18].try_into().unwrap());
        assert_eq!(crc32(&bytes[35..35 + size]), crc);
    }
}
