//! Scenes at the size of real glTF models and beyond: a million triangles
//! render (with a BVH whose build time is reported); more triangles than a
//! storage buffer of maxStorageBufferRange (128 MiB on lavapipe) holds still
//! render, since triangles are a texel image; and their vertex normals, a
//! storage buffer, fail with a message naming the buffer and the limit
//! instead of crashing the driver.

use crate::support;

use glam::DVec3;
use penumbra::render::{Accel, KernelOptions, RenderError};
use penumbra::scene::{Mesh, Scene, Shape};
use penumbra::vulkan::{Context, ContextOptions};

/// Bytes of one triangle on the GPU (render::layout::Triangle), and of one
/// triangle's vertex normals (render::layout::VertexNormals).
const TRIANGLE_BYTES: u64 = 48;

/// A flat-shaded `n`×`n` grid of quads (2·n² triangles) under the bunny
/// scene's camera, gently rippled so that it is not one plane. No vertex
/// normals, to keep memory down.
fn grid(n: u32) -> Mesh {
    let side = n + 1;
    let mut positions = Vec::with_capacity((side * side) as usize);
    for j in 0..side {
        for i in 0..side {
            let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
            let y = 0.05 * (u * 40.0).sin() * (v * 40.0).cos();
            positions.push(DVec3::new(-5.0 + 10.0 * u, y, -5.0 + 10.0 * v));
        }
    }
    let mut indices = Vec::with_capacity(2 * (n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let a = j * side + i;
            let (b, c, d) = (a + 1, a + side, a + side + 1);
            indices.push([a, c, b]);
            indices.push([b, c, d]);
        }
    }
    Mesh {
        uvs: vec![],
        colours: None,
        tangents: None,
        positions,
        normals: None,
        indices,
    }
}

/// The bunny scene with the bunny replaced by `mesh`, at `size`×`size` pixels.
fn scene_with(mesh: Mesh, size: u32) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bunny_scene.glb");
    let mut scene = support::load(&path);
    let bunny = scene
        .objects
        .iter_mut()
        .find(|o| matches!(&o.shape, Shape::Mesh(m) if m.indices.len() > 2))
        .expect("the bunny");
    bunny.shape = Shape::Mesh(mesh);
    scene.camera.width = size;
    scene.camera.height = size;
    scene.validate().expect("valid scene");
    scene
}

#[test]
fn a_million_triangles_render_with_a_bvh() {
    // 2·707² = 999,698 triangles (plus the 2 of the ground).
    let scene = scene_with(grid(707), 64);
    assert!(scene.triangle_count() > 999_000);
    let mut r = support::renderer();
    let before = r.kernel();
    r.set_kernel(KernelOptions::default());
    let frame = r.render_scene(&scene);
    r.set_kernel(before);
    let frame = frame.expect("a million triangles render");
    let s = frame.stats;
    assert_eq!(s.primary_rays, 64 * 64);
    assert!(
        s.timings.accel_build.as_nanos() > 0,
        "BVH build time reported"
    );
    assert!(s.bvh_nodes > 999_000 / 4, "{} nodes", s.bvh_nodes);
    assert!(s.bvh_bytes > 0);
    let hits = frame.image.pixels.iter().filter(|p| p[3] == 1.0).count();
    assert!(
        hits > 64 * 64 / 2,
        "the grid fills most of the view: {hits}"
    );
    eprintln!(
        "1M triangles: BVH build {:?}, {} nodes, depth {}, {:.1} MiB; render 64x64 {:?}",
        s.timings.accel_build,
        s.bvh_nodes,
        s.bvh_depth,
        s.bvh_bytes as f64 / 1048576.0,
        s.timings.render
    );
}

/// The device's maxStorageBufferRange, and the side `n` of a grid whose
/// 2·n² triangles need more than min(that, lavapipe's 128 MiB) at 48 bytes
/// each (a device with a larger limit takes the tests' scenes whole).
fn over_storage_limit() -> (u64, u32) {
    let limit = Context::new(&ContextOptions::default())
        .expect("Vulkan device")
        .limits()
        .max_storage_buffer_range;
    // Just over lavapipe's 128 MiB (2,796,203 triangles), or over the
    // device's limit when that is smaller.
    let lavapipe_limit = 128 << 20;
    let triangles = limit.min(lavapipe_limit) / TRIANGLE_BYTES + 1;
    let n = ((triangles as f64 / 2.0).sqrt().ceil()) as u32;
    (limit, n)
}

#[test]
fn triangles_beyond_max_storage_buffer_range_render() {
    // Triangles are a texel image (src/vulkan/image.rs), whose limit is
    // maxImageDimension2D rows of 4096 texels (1 GiB on lavapipe), not
    // maxStorageBufferRange: a mesh of more than 128 MiB renders.
    let (limit, n) = over_storage_limit();
    let scene = scene_with(grid(n), 16);
    let bytes = scene.triangle_count() as u64 * TRIANGLE_BYTES;
    assert!(bytes > limit.min(128 << 20));
    let mut r = support::renderer();
    let before = r.kernel();
    r.set_kernel(KernelOptions::default());
    let frame = r.render_scene(&scene);
    r.set_kernel(before);
    let frame = frame.expect("a triangle image over 128 MiB renders");
    let hits = frame.image.pixels.iter().filter(|p| p[3] == 1.0).count();
    assert!(
        hits > 16 * 16 / 2,
        "the grid fills most of the view: {hits}"
    );
}

#[test]
fn a_vertex_normal_buffer_beyond_max_storage_buffer_range_fails_clearly() {
    // The same mesh with vertex normals: their storage buffer (48 bytes a
    // triangle, like the triangles) is over the limit.
    let (limit, n) = over_storage_limit();
    let mut mesh = grid(n);
    mesh.normals = Some(vec![DVec3::Y; mesh.positions.len()]);
    let scene = scene_with(mesh, 16);
    let bytes = scene.triangle_count() as u64 * TRIANGLE_BYTES;
    let mut r = support::renderer();
    let before = r.kernel();
    // Brute force: the buffer check does not depend on the BVH, and
    // skipping a 2.8M-triangle build keeps the test quick.
    r.set_kernel(KernelOptions {
        accel: Accel::BruteForce,
        ..before
    });
    let result = r.upload(&scene).map(|_| ());
    r.set_kernel(before);
    if bytes <= limit {
        // A device with a larger limit (a GPU) takes the scene.
        result.expect("the device's limit is larger than the buffer");
        return;
    }
    let err = result.expect_err("a buffer over the limit must fail");
    let message = err.to_string();
    eprintln!("{message}");
    assert!(matches!(err, RenderError::Vulkan(_)), "{err:?}");
    assert!(
        message.contains("'vertex normals'"),
        "names the buffer: {message}"
    );
    assert!(
        message.contains("maxStorageBufferRange"),
        "names the limit: {message}"
    );
    let limit_mib = format!("{:.1} MiB", limit as f64 / 1048576.0);
    assert!(message.contains(&limit_mib), "gives the limit: {message}");
}
