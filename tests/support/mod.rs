//! Shared helpers for the GPU tests. They need a Vulkan device (lavapipe in
//! CI) and fail loudly when there is none; they never skip.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

use penumbra::loaders::{self, LoadOptions};
use penumbra::render::{Frame, Renderer, RendererOptions};
use penumbra::scene::Scene;

/// One renderer per test binary: opening the device and compiling kernels
/// costs far more than the small test renders.
pub fn renderer() -> std::sync::MutexGuard<'static, Renderer> {
    static R: OnceLock<Mutex<Renderer>> = OnceLock::new();
    R.get_or_init(|| {
        let opts = RendererOptions {
            validation: std::env::var("PENUMBRA_VALIDATION").as_deref() == Ok("1"),
            ..Default::default()
        };
        Mutex::new(Renderer::new(&opts).unwrap_or_else(|e| {
            panic!("GPU tests need a Vulkan device (run tools/setup.sh to install lavapipe): {e}")
        }))
    })
    .lock()
    .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Renders a validated scene.
pub fn render(scene: &Scene) -> Frame {
    scene.validate().expect("test scene is valid");
    renderer().render(scene).expect("render")
}

/// Writes `json` to a fresh temporary directory as `scene.json` (plus any
/// extra files) and returns the directory and the scene path.
pub fn write_scene(json: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("scene.json");
    std::fs::write(&path, json).expect("write scene");
    (dir, path)
}

/// Loads a JSON scene given as text.
pub fn load_json(json: &str) -> Scene {
    let (_dir, path) = write_scene(json);
    load(&path)
}

/// Loads a scene file with default options.
pub fn load(path: &Path) -> Scene {
    loaders::load_scene(path, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{e}"))
        .scene
}

/// Asserts two colours agree within `tol` per channel.
#[track_caller]
pub fn assert_rgb(got: [f32; 4], want: [f64; 3], tol: f64) {
    for c in 0..3 {
        assert!(
            (got[c] as f64 - want[c]).abs() <= tol,
            "channel {c}: got {:?}, want {:?} (tol {tol})",
            &got[..3],
            want
        );
    }
}
