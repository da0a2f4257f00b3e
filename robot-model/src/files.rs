//! Reading input files a user hands us (robot profiles, scenarios, recordings) without trusting
//! them: only regular files are opened, and never more than a size limit is read.
//!
//! A path to `/dev/zero` would otherwise be read until memory runs out, and a FIFO would block
//! the reader forever. The kind is checked on the path before opening (a file swapped for a FIFO
//! between the check and the open is not caught: the check is for users' mistakes, not for
//! attackers with write access to the directory).
//!
//! ```
//! use robot_model::files::read_bounded;
//! let err = read_bounded(std::path::Path::new("/dev/zero"), 1 << 20).unwrap_err();
//! assert_eq!(err.kind(), std::io::ErrorKind::InvalidInput);
//! assert!(err.to_string().contains("not a regular file"));
//! ```

use std::io::{self, Read};
use std::path::Path;

/// Robot profiles and scenario files are text of a few kilobytes; this leaves ample room.
pub const TEXT_FILE_LIMIT: u64 = 4 << 20;

/// Reads the regular file at `path`, at most `limit` bytes. Anything else (a directory, a device,
/// a FIFO, a socket) or a longer file is an `InvalidInput` error whose text says why.
pub fn read_bounded(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        let what = if meta.is_dir() { "a directory" } else { "a device, FIFO or socket" };
        return Err(io::Error::new(io::ErrorKind::InvalidInput, format!("not a regular file ({what})")));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)?.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("larger than the {limit}-byte limit for this kind of file"),
        ));
    }
    Ok(bytes)
}

/// [`read_bounded`] for UTF-8 text.
pub fn read_text_bounded(path: &Path, limit: u64) -> io::Result<String> {
    String::from_utf8(read_bounded(path, limit)?)
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, format!("not UTF-8 text: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regular_files_are_read_up_to_the_limit() {
        let dir = std::env::temp_dir().join(format!("explobot-files-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("a.ron");
        std::fs::write(&file, b"0123456789").unwrap();
        assert_eq!(read_bounded(&file, 10).unwrap(), b"0123456789");
        let err = read_bounded(&file, 9).unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        assert!(err.to_string().contains("9-byte limit"), "{err}");
        let err = read_bounded(&dir, 100).unwrap_err();
        assert!(err.to_string().contains("a directory"), "{err}");
        std::fs::write(&file, [0xff, 0xfe]).unwrap();
        assert_eq!(read_text_bounded(&file, 10).unwrap_err().kind(), io::ErrorKind::InvalidData);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn devices_are_refused_without_reading() {
        let err = read_bounded(Path::new("/dev/zero"), u64::MAX).unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        assert!(read_bounded(Path::new("/nonexistent/x.ron"), 10).is_err());
    }
}
