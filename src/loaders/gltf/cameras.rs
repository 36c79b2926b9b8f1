//! Which of a glTF file's cameras penumbra renders from (`--camera`): the
//! first one placed in the default scene (the default), one chosen by its
//! index in `cameras` or by its name, or the framing view
//! ([`super::framing`]) even when the file has cameras. A camera under an
//! animated node is used in its static pose, and a note says so.

use std::path::Path;

use super::GltfCamera;
use crate::SceneError;

/// `--camera`: which view to render a glTF file from.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum CameraChoice {
    /// The file's first camera (depth-first in the default scene), else
    /// the framing camera.
    #[default]
    File,
    /// The framing camera, even if the file has cameras (`framing`).
    Framing,
    /// `cameras[i]` of the file.
    Index(usize),
    /// The camera of this `name`.
    Name(String),
}

impl CameraChoice {
    /// `--camera`'s value: `framing`, an index, or a camera's name.
    pub fn parse(value: &str) -> CameraChoice {
        match value {
            "framing" => CameraChoice::Framing,
            v => match v.parse() {
                Ok(i) => CameraChoice::Index(i),
                Err(_) => CameraChoice::Name(v.to_string()),
            },
        }
    }
}

/// A camera placed by a node of the default scene.
#[derive(Clone, Debug)]
pub struct PlacedCamera {
    /// Its index in the file's `cameras`.
    pub index: usize,
    /// Its `name`, if it has one.
    pub name: Option<String>,
    /// Where it stands and how it projects.
    pub camera: GltfCamera,
    /// Its node, or one above it, is the target of an animation: this is
    /// its static pose.
    pub animated: bool,
}

impl PlacedCamera {
    /// `cameras[2] 'Top'`, for messages.
    pub fn label(&self) -> String {
        match &self.name {
            Some(n) => format!("cameras[{}] '{n}'", self.index),
            None => format!("cameras[{}]", self.index),
        }
    }
}

/// The camera `choice` picks from `placed` (in scene order): `None` for
/// the framing view; an error naming `--camera` and the cameras the file
/// has when there is no such camera.
pub(super) fn choose<'c>(
    path: &Path,
    choice: &CameraChoice,
    placed: &'c [PlacedCamera],
) -> Result<Option<&'c PlacedCamera>, SceneError> {
    let found = match choice {
        CameraChoice::File => return Ok(placed.first()),
        CameraChoice::Framing => return Ok(None),
        CameraChoice::Index(i) => placed.iter().find(|c| c.index == *i),
        CameraChoice::Name(n) => placed.iter().find(|c| c.name.as_deref() == Some(n)),
    };
    if found.is_some() {
        return Ok(found);
    }
    let wanted = match choice {
        CameraChoice::Index(i) => {
            format!("--camera {i}: no node of the default scene places cameras[{i}]")
        }
        CameraChoice::Name(n) => {
            format!("--camera '{n}': no camera of that name in the default scene")
        }
        _ => unreachable!("returned above"),
    };
    let list: Vec<String> = placed.iter().take(10).map(PlacedCamera::label).collect();
    let more = placed.len().saturating_sub(10);
    let has = match (list.is_empty(), more) {
        (true, _) => "it places no camera; use --camera framing or leave --camera out".into(),
        (false, 0) => format!("its cameras: {}", list.join(", ")),
        (false, n) => format!("its cameras: {} and {n} more", list.join(", ")),
    };
    Err(SceneError::new(path, "cameras", format!("{wanted}; {has}")))
}
