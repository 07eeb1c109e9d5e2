//! Reading and writing files with a size cap.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::ExchangeError;

/// Largest file the `read_file` helpers read (64 MiB).
pub const MAX_FILE_BYTES: u64 = 64 << 20;

/// Reads a regular file of at most [`MAX_FILE_BYTES`] as UTF-8 text. The size is checked on
/// what is read through the handle (at most the limit plus one byte), not on the metadata
/// alone, so a file that grows while it is read is still refused.
pub(crate) fn read_text(path: &Path) -> Result<String, ExchangeError> {
    read_text_limited(path, MAX_FILE_BYTES)
}

pub(crate) fn read_text_limited(path: &Path, limit: u64) -> Result<String, ExchangeError> {
    read_text_bounded(path, limit).map_err(|e| match e {
        BoundedReadError::Io(source) => ExchangeError::Io {
            path: path.to_path_buf(),
            source,
        },
        BoundedReadError::NotRegularFile { .. } => ExchangeError::NotRegularFile {
            path: path.to_path_buf(),
        },
        BoundedReadError::TooLarge { limit } => ExchangeError::FileTooLarge {
            path: path.to_path_buf(),
            limit,
        },
        BoundedReadError::NotText { offset } => ExchangeError::NotText {
            path: path.to_path_buf(),
            offset,
        },
    })
}

/// Why [`read_text_bounded`] refused a file.
#[derive(Debug)]
pub enum BoundedReadError {
    /// It could not be opened or read.
    Io(std::io::Error),
    /// A folder (`folder`), a FIFO, a socket or a device.
    NotRegularFile {
        /// True for a folder.
        folder: bool,
    },
    /// More than `limit` bytes.
    TooLarge {
        /// The limit.
        limit: u64,
    },
    /// Not UTF-8: the first invalid byte.
    NotText {
        /// Its offset.
        offset: usize,
    },
}

/// Reads a regular file of at most `limit` bytes as UTF-8 text, the one bounded reader of the
/// project. The file is opened without blocking (opening a FIFO would block until a writer
/// appears) and its kind checked through the handle; the size is checked on what is read
/// through the handle (at most `limit + 1` bytes), so a file that grows while it is read is
/// still refused.
pub fn read_text_bounded(path: &Path, limit: u64) -> Result<String, BoundedReadError> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(rustix::fs::OFlags::NONBLOCK.bits() as i32);
    }
    let file: File = options.open(path).map_err(BoundedReadError::Io)?;
    let meta = file.metadata().map_err(BoundedReadError::Io)?;
    if !meta.is_file() {
        return Err(BoundedReadError::NotRegularFile {
            folder: meta.is_dir(),
        });
    }
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(BoundedReadError::Io)?;
    if bytes.len() as u64 > limit {
        return Err(BoundedReadError::TooLarge { limit });
    }
    String::from_utf8(bytes).map_err(|e| BoundedReadError::NotText {
        offset: e.utf8_error().valid_up_to(),
    })
}

/// Writes `text` to `path` (created or truncated).
pub(crate) fn write_text(path: &Path, text: &str) -> Result<(), ExchangeError> {
    std::fs::write(path, text).map_err(|source| ExchangeError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_directories_large_files_and_binary() {
        let dir =
            std::env::temp_dir().join(format!("nurbspring-exchange-fsio-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        assert!(matches!(
            read_text(&dir),
            Err(ExchangeError::NotRegularFile { .. })
        ));
        let big = dir.join("big.txt");
        std::fs::write(&big, "x".repeat(101)).unwrap();
        assert!(matches!(
            read_text_limited(&big, 100),
            Err(ExchangeError::FileTooLarge { limit: 100, .. })
        ));
        assert_eq!(read_text_limited(&big, 101).unwrap().len(), 101);
        let bin = dir.join("bin.dat");
        std::fs::write(&bin, [b'a', 0xff, b'b']).unwrap();
        assert!(matches!(
            read_text(&bin),
            Err(ExchangeError::NotText { offset: 1, .. })
        ));
        assert!(matches!(
            read_text(&dir.join("absent")),
            Err(ExchangeError::Io { .. })
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
