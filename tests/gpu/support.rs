//! Shared helpers for the GPU tests. They need a Vulkan device (lavapipe in
//! CI) and fail loudly when there is none; they never skip.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

use penumbra::loaders::{self, LoadOptions};
use penumbra::render::{Frame, Renderer, RendererOptions};
use penumbra::scene::Scene;

/// One renderer per test binary (tests/gpu: every module's tests): opening
/// the device and compiling kernels costs far more than the small test
/// renders. Tests that switch its kernel, stage memory, band cap, shadow fusion,
/// stage words or stage profiling switch them back
/// before they release the lock; if a test panicked while holding it, the
/// next caller gets the renderer back with the defaults restored, so that
/// one failure does not leak its settings into the other modules' tests.
pub fn renderer() -> std::sync::MutexGuard<'static, Renderer> {
    static R: OnceLock<Mutex<Renderer>> = OnceLock::new();
    let r = R.get_or_init(|| {
        let opts = RendererOptions {
            validation: std::env::var("PENUMBRA_VALIDATION").as_deref() == Ok("1"),
            ..Default::default()
        };
        Mutex::new(Renderer::new(&opts).unwrap_or_else(|e| {
            panic!("GPU tests need a Vulkan device (run tools/setup.sh to install lavapipe): {e}")
        }))
    });
    r.lock().unwrap_or_else(|poisoned| {
        r.clear_poison();
        let mut guard = poisoned.into_inner();
        guard.set_kernel(RendererOptions::default().kernel);
        guard.set_stage_memory(penumbra::render::tiles::DEFAULT_STAGE_MEMORY);
        guard.set_fused_shadows(true);
        guard.set_stage_words(true);
        guard.set_profile_stages(false);
        guard.set_image_band_bytes(u64::MAX);
        guard.set_texture_capacity(u64::MAX);
        guard
    })
}

/// Renders a validated scene.
pub fn render(scene: &Scene) -> Frame {
    scene.validate().expect("test scene is valid");
    renderer().render_scene(scene).expect("render")
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

/// The scene file `file` of the repository's `scenes/` at `width`×`height`,
/// validated.
pub fn repo_scene(file: &str, width: u32, height: u32) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(file);
    let mut scene = load(&path);
    scene.camera.width = width;
    scene.camera.height = height;
    scene.validate().expect("valid");
    scene
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

/// Renders on the GPU with `kernel` and `sampling`, holding the shared
/// renderer's lock for the whole step (the kernel is switched back after).
pub fn render_with(
    scene: &Scene,
    kernel: penumbra::render::KernelOptions,
    sampling: penumbra::render::Sampling,
) -> Frame {
    scene.validate().expect("test scene is valid");
    let mut r = renderer();
    let before = r.kernel();
    r.set_kernel(kernel);
    let result = r.upload(scene).and_then(|up| {
        let (w, h) = up.size();
        r.render(
            &up,
            penumbra::render::RenderRequest::progressive(w, h, &sampling, &mut |_| {}),
        )
        .map(|r| r.frame)
    });
    r.set_kernel(before);
    result.expect("render")
}

/// The benchmark scene (`scenes/bunny_scene.glb`, 1024×1024) with ambient
/// terms that tell its two meshes apart, for comparing with Embree's counts:
/// with the light's ambient 0.1, an unlit ground pixel is exactly 0.05 and an
/// unlit bunny pixel exactly 0.1, and lit pixels are brighter.
pub fn tagged_bunny_scene() -> Scene {
    use glam::Vec3;
    use penumbra::scene::{Phong, Shader, Shape};
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bunny_scene.glb");
    let mut scene = load(&path);
    assert_eq!((scene.camera.width, scene.camera.height), (1024, 1024));
    scene.lights[0].ambient = Vec3::splat(0.1);
    let phong = |ka: f32| {
        Shader::Phong(Phong {
            textures: Default::default(),
            ambient: Vec3::splat(ka),
            diffuse: Vec3::splat(0.8),
            specular: Vec3::ZERO,
            shininess: 1.0,
        })
    };
    scene.shaders = vec![phong(0.5), phong(1.0)];
    for o in &mut scene.objects {
        let Shape::Mesh(m) = &o.shape else {
            panic!("the scene has meshes only")
        };
        o.shader = if m.indices.len() == 2 { 0 } else { 1 };
    }
    scene
}

/// (bunny hits, ground hits, unlit bunny pixels, unlit ground pixels) of a
/// render of [`tagged_bunny_scene`]. The ground is lit at cos = 2/3; bunny
/// points lit at exactly that cosine are too few to matter.
pub fn bunny_counts(image: &penumbra::render::Image) -> [usize; 4] {
    let px = &image.pixels;
    let count = |f: &dyn Fn(f32) -> bool| px.iter().filter(|p| p[3] == 1.0 && f(p[0])).count();
    let ground_lit = 0.05 + 0.8 * 2.0 / 3.0;
    [
        count(&|r| r == 0.1 || (r > 0.1 && (r - ground_lit).abs() > 1e-5)),
        count(&|r| r == 0.05 || (r - ground_lit).abs() <= 1e-5),
        count(&|r| r == 0.1),
        count(&|r| r == 0.05),
    ]
}

/// Orthographic camera at height 1 looking straight down (−Y) at the plane
/// y = 0, image up = −Z, covering x, z in [−half, half], `px` pixels square.
pub fn top_down(half: f64, px: u32) -> penumbra::scene::Camera {
    use glam::{DMat3, DVec3};
    penumbra::scene::Camera {
        position: DVec3::new(0.0, 1.0, 0.0),
        orientation: DMat3::from_cols(DVec3::X, DVec3::NEG_Z, DVec3::Y),
        projection: penumbra::scene::Projection::Orthographic { half_height: half },
        width: px,
        height: px,
    }
}

/// Orthographic camera at z = 5 looking along −Z (image right +X, up +Y),
/// covering y in [−half, half], `width` × `height` pixels.
pub fn front_on(half: f64, width: u32, height: u32) -> penumbra::scene::Camera {
    use glam::{DMat3, DVec3};
    penumbra::scene::Camera {
        position: DVec3::new(0.0, 0.0, 5.0),
        orientation: DMat3::IDENTITY,
        projection: penumbra::scene::Projection::Orthographic { half_height: half },
        width,
        height,
    }
}
