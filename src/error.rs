//! Errors about the scene: each names the file and the field path, so a user
//! can find the offending value without reading a stack trace.

use std::fmt;
use std::path::{Path, PathBuf};

/// A problem with a scene: which file, which field (a JSON-style path such as
/// `objects[2].radius`, empty when the file as a whole is at fault), and what.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// The file the value came from (the scene file, or a referenced glTF file).
    pub file: PathBuf,
    /// Path of the offending field inside that file, e.g. `camera.fov`.
    pub field: String,
    /// What is wrong, in plain words.
    pub message: String,
}

impl SceneError {
    /// An error about `field` of `file`.
    pub fn new(file: &Path, field: impl Into<String>, message: impl Into<String>) -> Self {
        SceneError {
            file: file.to_path_buf(),
            field: field.into(),
            message: message.into(),
        }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.field.is_empty() {
            write!(f, "{}: {}", self.file.display(), self.message)
        } else {
            write!(
                f,
                "{}: {}: {}",
                self.file.display(),
                self.field,
                self.message
            )
        }
    }
}

impl std::error::Error for SceneError {}
