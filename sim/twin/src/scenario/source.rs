//! Where a value stands in a scenario's text, as ron's own parser finds it, and the
//! [`ScenarioError`] that says so.
//!
//! [`parse`] deserializes through [`serde_path_to_error`], so a failing value comes back with
//! its path (`obstacles[2].radius`). A check that fails inside serde (the validators in
//! `values`) is placed at the start of the value that path names; any other error (syntax, a
//! wrong type, an unknown field) keeps ron's own position. [`position_of`] finds the start of a
//! value by its path for the checks that need more than one value (a `GoTo` off a grid that
//! depends on the robot profile): it walks the text again with ron and stops there.
//!
//! Invariant: positions come from ron's parser, so strings, comments and a key written twice
//! (two `GuiDisconnect(at_s: …)` faults) never confuse them; a path that is not in the text
//! gives `None` and callers fall back to 1:1.

use std::fmt;

use serde::de::{DeserializeOwned, DeserializeSeed, Deserializer, Error as _, IgnoredAny, MapAccess};
use serde::de::{SeqAccess, Visitor};

/// One step of a path into the scenario: a field name or a list index.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Key {
    /// A struct field (`room`, `at_s`).
    Field(String),
    /// An element of a list or tuple, from 0.
    Index(usize),
}

/// A path written the way a reader finds it: `faults[1].at_s`.
pub struct PathText<'a>(pub &'a [Key]);

impl fmt::Display for PathText<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, key) in self.0.iter().enumerate() {
            match key {
                Key::Field(name) if i == 0 => write!(f, "{name}")?,
                Key::Field(name) => write!(f, ".{name}")?,
                Key::Index(n) => write!(f, "[{n}]")?,
            }
        }
        Ok(())
    }
}

/// A scenario that could not be loaded: where and why.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioError {
    /// The file (or label) the text came from.
    pub file: String,
    /// 1-based line, when known.
    pub line: usize,
    /// 1-based column, when known.
    pub column: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}: {}", self.file, self.line, self.column, self.message)
    }
}

impl std::error::Error for ScenarioError {}

impl ScenarioError {
    /// An error about the whole file (it cannot be read): 1:1.
    pub fn whole_file(file: &str, message: impl Into<String>) -> Self {
        ScenarioError { file: file.to_string(), line: 1, column: 1, message: message.into() }
    }

    /// An error about the value at `path` in `text` (1:1 when the text does not have it).
    pub fn at(file: &str, text: &str, path: &[Key], message: String) -> Self {
        let (line, column) = position_of(text, path).unwrap_or((1, 1));
        ScenarioError { file: file.to_string(), line, column, message }
    }
}

/// The path step of field `name`.
pub fn field(name: &str) -> Key {
    Key::Field(name.to_string())
}

/// Deserializes `text` (from `file`); see the module docs for where errors point.
pub fn parse<T: DeserializeOwned>(text: &str, file: &str) -> Result<T, ScenarioError> {
    let at = |e: ron::error::SpannedError| ScenarioError {
        file: file.to_string(),
        line: e.span.start.line,
        column: e.span.start.col,
        message: e.code.to_string(),
    };
    let mut de = ron::Deserializer::from_str(text).map_err(at)?;
    let value = match serde_path_to_error::deserialize::<_, T>(&mut de) {
        Ok(value) => value,
        Err(e) => {
            let path = keys(e.path());
            let spanned = de.span_error(e.into_inner());
            return Err(match &spanned.code {
                // A validator's message: it is about the whole value at `path`.
                ron::Error::Message(message) => {
                    let (line, column) =
                        position_of(text, &path).unwrap_or((spanned.span.start.line, spanned.span.start.col));
                    let message = format!("{}: {message}", PathText(&path));
                    ScenarioError { file: file.to_string(), line, column, message }
                }
                _ => at(spanned),
            });
        }
    };
    de.end().map_err(|e| at(de.span_error(e)))?;
    Ok(value)
}

/// The path as [`Key`]s (enum variants are not steps in the text: `Circle(radius: …)` is read
/// as a struct).
fn keys(path: &serde_path_to_error::Path) -> Vec<Key> {
    let mut out = Vec::new();
    for segment in path {
        match segment {
            serde_path_to_error::Segment::Seq { index } => out.push(Key::Index(*index)),
            serde_path_to_error::Segment::Map { key } => out.push(Key::Field(key.clone())),
            serde_path_to_error::Segment::Enum { .. } => {}
            _ => break,
        }
    }
    out
}

/// The marker error [`Find`] stops the parser with.
const FOUND: &str = "\u{0}found";

/// Line and column (1-based) where the value at `path` starts in `text`, `None` when the text
/// has no such value.
pub fn position_of(text: &str, path: &[Key]) -> Option<(usize, usize)> {
    match ron::Options::default().from_str_seed(text, Find { path }) {
        // The parser stops with its cursor on the first character of the value.
        Err(e) if matches!(&e.code, ron::Error::Message(m) if m == FOUND) => {
            Some((e.span.end.line, e.span.end.col))
        }
        _ => None,
    }
}

/// Walks any RON value down `path` and fails with [`FOUND`] when it gets there.
struct Find<'p> {
    path: &'p [Key],
}

impl<'de> DeserializeSeed<'de> for Find<'_> {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        if self.path.is_empty() {
            return Err(D::Error::custom(FOUND));
        }
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Find<'_> {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a value containing the path")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let Some((Key::Field(want), rest)) = self.path.split_first() else {
            return Ok(());
        };
        while let Some(key) = map.next_key::<String>()? {
            if key == *want {
                return map.next_value_seed(Find { path: rest });
            }
            map.next_value::<IgnoredAny>()?;
        }
        Ok(())
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let Some((Key::Index(want), rest)) = self.path.split_first() else {
            return Ok(());
        };
        for _ in 0..*want {
            if seq.next_element::<IgnoredAny>()?.is_none() {
                return Ok(());
            }
        }
        seq.next_element_seed(Find { path: rest }).map(|_| ())
    }

    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }

    fn visit_newtype_struct<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "Scenario(\n  name: \"x\", // room: not here\n  faults: [\n    GuiDisconnect(at_s: 1.0),\n    GuiDisconnect(at_s: 2.0),\n  ],\n  expect: (reached: Some((1, 2))),\n)";

    fn field(s: &str) -> Key {
        Key::Field(s.to_string())
    }

    #[test]
    fn finds_values_by_path() {
        let second = [field("faults"), Key::Index(1), field("at_s")];
        assert_eq!(position_of(TEXT, &second), Some((5, 25)));
        assert_eq!(position_of(TEXT, &[field("faults"), Key::Index(1)]), Some((5, 5)));
        assert_eq!(position_of(TEXT, &[field("expect"), field("reached")]), Some((7, 21)));
        assert_eq!(position_of(TEXT, &[field("room")]), None);
        assert_eq!(position_of(TEXT, &[field("faults"), Key::Index(2)]), None);
        assert_eq!(PathText(&second).to_string(), "faults[1].at_s");
    }
}
