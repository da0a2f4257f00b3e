//! `--map FILE`: a known map, read from a text file, that a session starts from instead of an
//! all-unknown map.
//!
//! Format (the map values of the link protocol, `protocols.md` §1, as [`Map::parse`] reads them):
//! - one line per row, top row first (row = `x`, growing downward); one digit per cell, left
//!   to right (column = `y`, growing rightward);
//! - `0` obstacle, `1` free, `2` unknown, `3` waypoint, `4` destination, `5` robot;
//! - every row has the same number of cells; 1 to 256 rows and columns;
//! - spaces, tabs and commas between digits are ignored; blank lines and lines starting with `#`
//!   are skipped (comments);
//! - at most one `5`: if present it is the robot's start cell (and the heading comes from
//!   `--heading`); `3` and `4` are read as free cells (a trajectory is not part of a map);
//! - UTF-8 text, at most [`MAP_FILE_LIMIT`] bytes, from a regular file (a FIFO or a device is
//!   refused before anything is read).
//!
//! ```text
//! # the living room, 4 x 6; the robot starts top-left
//! 5 1 1 1 1 1
//! 1 0 0 1 2 2
//! 1 0 0 1 2 2
//! 1 1 1 1 1 1
//! ```
//!
//! Errors say where: `room.map:3:5: '7' is not a cell value (0..=5)` (file, 1-based line and
//! column in characters, problem).
//!
//! ```
//! use cute::map_file::{MapFileError, load_map};
//! let dir = std::env::temp_dir().join(format!("cute-map-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir).unwrap();
//! let path = dir.join("room.map");
//! std::fs::write(&path, "# two rows\n5 1 1\n1 0 2\n").unwrap();
//! let map = load_map(&path).unwrap();
//! assert_eq!((map.rows(), map.cols(), map.robot()), (2, 3, Some((0, 0))));
//! std::fs::write(&path, "111\n1x1\n").unwrap();
//! let err = load_map(&path).unwrap_err();
//! assert!(matches!(err, MapFileError::Parse { line: 2, column: 2, .. }));
//! assert!(err.to_string().ends_with("room.map:2:2: 'x' is not a cell value (0..=5)"));
//! std::fs::remove_dir_all(&dir).unwrap();
//! ```

use std::path::{Path, PathBuf};

use robot_model::files::read_text_bounded;
use thiserror::Error;

use crate::map::{Map, MapError, TextProblem};

/// The largest map file read: a 256 × 256 map with a separator after every digit is 128 KiB;
/// this leaves room for comments.
pub const MAP_FILE_LIMIT: u64 = 1 << 20;

/// Why a map file was refused.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum MapFileError {
    /// The file could not be read (missing, not a regular file, too large, not UTF-8).
    #[error("{}: cannot read the map: {message}", .path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The reason.
        message: String,
    },
    /// The text is wrong at one place.
    #[error("{}:{line}:{column}: {problem}", .path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column, in characters.
        column: usize,
        /// What is wrong there.
        problem: TextProblem,
    },
    /// The file holds no row (empty, or only blank lines and comments).
    #[error("{}: no map rows (the file is empty or holds only comments)", .path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// The rows parse but do not make a map (e.g. more than 256 columns).
    #[error("{}: {error}", .path.display())]
    Map {
        /// The file.
        path: PathBuf,
        /// Why.
        error: MapError,
    },
}

/// Reads and parses the map file at `path` (format in the module docs). Waypoints and the
/// destination are turned into free cells; a robot cell is kept.
pub fn load_map(path: &Path) -> Result<Map, MapFileError> {
    let text = read_text_bounded(path, MAP_FILE_LIMIT)
        .map_err(|e| MapFileError::Read { path: path.to_path_buf(), message: e.to_string() })?;
    parse_map_file(path, &text)
}

/// Parses map text that came from `path` (used in error messages only).
pub fn parse_map_file(path: &Path, text: &str) -> Result<Map, MapFileError> {
    let path = path.to_path_buf();
    match Map::parse(text) {
        Ok(mut map) => {
            map.clear_trajectory();
            Ok(map)
        }
        Err(MapError::Text { line, column, problem }) => {
            Err(MapFileError::Parse { path, line, column, problem })
        }
        Err(MapError::BadSize { rows: 0, .. } | MapError::BadSize { cols: 0, .. }) => {
            Err(MapFileError::Empty { path })
        }
        Err(error) => Err(MapFileError::Map { path, error }),
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::map::CellValue;

    fn parse(text: &str) -> Result<Map, MapFileError> {
        parse_map_file(Path::new("room.map"), text)
    }

    #[test]
    fn a_good_file_with_comments_separators_and_a_trajectory() {
        let map = parse("# room\r\n\r\n5,1,3\r\n1 0 4\r\n2\t2\t2\r\n").unwrap();
        assert_eq!((map.rows(), map.cols()), (3, 3));
        assert_eq!(map.robot(), Some((0, 0)));
        assert_eq!(map.to_text(), "511\n101\n222\n", "waypoint and destination read as free");
        assert_eq!(map.destination(), None);
        assert_eq!(map.get(1, 1), Some(CellValue::Obstacle));
    }

    #[test]
    fn errors_name_file_line_and_column() {
        let err = parse("111\n111\n11 9\n").unwrap_err();
        assert_eq!(err.to_string(), "room.map:3:4: '9' is not a cell value (0..=5)");
        let err = parse("# c\n1111\n111\n").unwrap_err();
        assert_eq!(err.to_string(), "room.map:3:4: 3 cells on this row, expected 4 as on the first row");
        assert_eq!(
            parse("# only a comment\n\n").unwrap_err(),
            MapFileError::Empty { path: "room.map".into() }
        );
        let wide = "1".repeat(257);
        assert!(parse(&wide).unwrap_err().to_string().contains("257"), "too wide");
    }

    #[test]
    fn unreadable_files_are_errors_not_panics() {
        let err = load_map(Path::new("/dev/zero")).unwrap_err();
        assert!(err.to_string().contains("not a regular file"), "{err}");
        let err = load_map(Path::new("/nonexistent/room.map")).unwrap_err();
        assert!(matches!(err, MapFileError::Read { .. }), "{err}");
    }
}
