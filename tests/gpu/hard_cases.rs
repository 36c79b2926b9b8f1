//! Numerically hard cases, ray by ray through the GPU's own intersection code
//! (Renderer::trace).

use crate::support;

use glam::{DMat3, DVec3, Vec3};
use penumbra::render::{HitKind, KernelOptions, TraceHit, TraceRay, TriangleTest};
use penumbra::scene::{Camera, Mesh, Object, Phong, Projection, Scene, Shader, Shape, Triangle};

fn scene_with(objects: Vec<Object>, eye: DVec3) -> Scene {
    Scene {
        textures: vec![],
        camera: Camera {
            position: eye,
            orientation: DMat3::IDENTITY,
            projection: Projection::Perspective { vfov_deg: 60.0 },
            width: 8,
            height: 8,
        },
        background: Vec3::ZERO,
        shaders: vec![Shader::Phong(Phong {
            textures: Default::default(),
            ambient: Vec3::ZERO,
            diffuse: Vec3::ONE,
            specular: Vec3::ZERO,
            shininess: 1.0,
        })],
        objects,
        lights: vec![],
    }
}

fn tri(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Object {
    Object {
        maps: Default::default(),
        shape: Shape::Triangle(Triangle {
            vertices: [a, b, c].map(DVec3::from_array),
        }),
        shader: 0,
    }
}

/// Traces `rays` with the default (watertight) triangle test.
fn trace(scene: &Scene, rays: &[TraceRay]) -> Vec<Option<TraceHit>> {
    trace_with(TriangleTest::default(), scene, rays)
}

/// Traces `rays` with triangle test `t`, holding the shared renderer for the
/// whole call so parallel tests cannot switch the kernel in between.
fn trace_with(t: TriangleTest, scene: &Scene, rays: &[TraceRay]) -> Vec<Option<TraceHit>> {
    scene.validate().unwrap();
    let mut r = support::renderer();
    let before = r.kernel();
    r.set_kernel(KernelOptions {
        triangle_test: t,
        ..before
    });
    let result = r.upload(scene).and_then(|up| r.trace(&up, rays));
    r.set_kernel(before);
    result.expect("trace")
}

#[test]
fn crack_case_on_the_shared_diagonal() {
    // Two triangles sharing the diagonal of a quad; the ray hits the diagonal.
    let quad = vec![
        tri([-5.0, -5.0, 0.0], [5.0, -5.0, 0.0], [5.0, 5.0, 0.0]),
        tri([-5.0, -5.0, 0.0], [5.0, 5.0, 0.0], [-5.0, 5.0, 0.0]),
    ];
    let d = [0.30458447f32, 0.30458447, -0.9024725].map(f64::from);
    let ray = TraceRay {
        origin: DVec3::new(0.0, 0.0, 10.0),
        dir: DVec3::from_array(d),
    };
    let hits = trace(&scene_with(quad, DVec3::new(0.0, 0.0, 10.0)), &[ray]);
    eprintln!("{hits:?}");
    let h = hits[0].expect("the ray must hit one of the two triangles");
    assert_eq!(h.kind, HitKind::Triangle);
}

/// Icosphere: icosahedron subdivided `levels` times, vertices on the unit
/// sphere, shared vertices exactly equal.
fn icosphere(levels: u32) -> Mesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut positions: Vec<DVec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| DVec3::from_array(*p).normalize())
    .collect();
    let mut indices: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut next = Vec::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<DVec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                positions.push(((positions[a as usize] + positions[b as usize]) * 0.5).normalize());
                positions.len() as u32 - 1
            })
        };
        for [a, b, c] in indices {
            let (ab, bc, ca) = (
                midpoint(a, b, &mut positions),
                midpoint(b, c, &mut positions),
                midpoint(c, a, &mut positions),
            );
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        indices = next;
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

/// Deterministic uniform numbers in [0, 1).
fn lcg(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Rays from random points inside a closed mesh (around `inside`, within
/// `spread`) aimed at points of its surface: on shared edges, at vertices,
/// and anywhere. Each must leave through the surface, so each must hit.
/// (Rays from outside would not do: one aimed at an edge of a convex mesh can
/// legitimately graze past it.)
fn leaks(t: TriangleTest, mesh: Mesh, inside: DVec3, spread: f64, n: usize, seed: u64) -> usize {
    let mut rnd = lcg(seed);
    let mut rays = Vec::with_capacity(n);
    for k in 0..n {
        let i = (rnd() * mesh.indices.len() as f64) as usize % mesh.indices.len();
        let [a, b, c] = mesh.indices[i];
        let (pa, pb, pc) = (
            mesh.positions[a as usize],
            mesh.positions[b as usize],
            mesh.positions[c as usize],
        );
        let target = match k % 3 {
            0 => pa + (pb - pa) * rnd(), // on an edge
            1 => pa,                     // a vertex
            _ => {
                let (u, v) = (rnd(), rnd());
                let (u, v) = if u + v > 1.0 {
                    (1.0 - u, 1.0 - v)
                } else {
                    (u, v)
                };
                pa + (pb - pa) * u + (pc - pa) * v
            }
        };
        let origin = inside + DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * spread;
        rays.push(TraceRay {
            origin,
            dir: (target - origin).normalize(),
        });
    }
    let scene = scene_with(
        vec![Object {
            maps: Default::default(),
            shape: Shape::Mesh(mesh),
            shader: 0,
        }],
        DVec3::new(0.0, 0.0, 10.0),
    );
    trace_with(t, &scene, &rays)
        .iter()
        .filter(|h| h.is_none())
        .count()
}

/// A closed axis-aligned cube of side 2 around the origin, 12 triangles.
fn cube() -> Mesh {
    let positions: Vec<DVec3> = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            )
        })
        .collect();
    let quads = [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ];
    let indices = quads
        .iter()
        .flat_map(|[a, b, c, d]| [[*a, *b, *c], [*a, *c, *d]])
        .collect();
    Mesh {
        uvs: vec![],
        colours: None,
        tangents: None,
        positions,
        normals: None,
        indices,
    }
}

/// A closed cylinder (radius 1, height 20) of 256 sides, each side two long
/// thin triangles (about 0.025 by 20), with fan caps of thin triangles too.
fn thin_cylinder() -> Mesh {
    let n = 256u32;
    let mut positions = Vec::new();
    for k in 0..n {
        let a = k as f64 / n as f64 * std::f64::consts::TAU;
        positions.push(DVec3::new(a.cos(), -10.0, a.sin()));
        positions.push(DVec3::new(a.cos(), 10.0, a.sin()));
    }
    let (bottom, top) = (2 * n, 2 * n + 1);
    positions.push(DVec3::new(0.0, -10.0, 0.0));
    positions.push(DVec3::new(0.0, 10.0, 0.0));
    let mut indices = Vec::new();
    for k in 0..n {
        let (b0, t0, b1, t1) = (2 * k, 2 * k + 1, 2 * ((k + 1) % n), 2 * ((k + 1) % n) + 1);
        indices.extend([[b0, t0, t1], [b0, t1, b1], [bottom, b0, b1], [top, t1, t0]]);
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

#[test]
fn closed_meshes_do_not_leak() {
    // 1.2 million rays aimed at shared edges, vertices and faces from inside.
    let cases = |t| {
        [
            (
                "icosphere",
                leaks(t, icosphere(3), DVec3::ZERO, 0.5, 400_000, 1),
            ),
            ("cube", leaks(t, cube(), DVec3::ZERO, 1.0, 400_000, 2)),
            (
                "thin cylinder",
                leaks(t, thin_cylinder(), DVec3::ZERO, 0.5, 400_000, 3),
            ),
        ]
    };
    for (name, n) in cases(TriangleTest::Watertight) {
        assert_eq!(n, 0, "{name}: {n} rays slipped through");
    }
    // The same rays do find the cracks of the seminar's Möller–Trumbore test,
    // so this test can tell a watertight test from one that is not.
    let mt: usize = cases(TriangleTest::UvFirst).iter().map(|c| c.1).sum();
    assert!(mt > 0, "Möller–Trumbore leaked nowhere?");
}

fn all_tests() -> [TriangleTest; 3] {
    [
        TriangleTest::Watertight,
        TriangleTest::UvFirst,
        TriangleTest::TFirst,
    ]
}

#[track_caller]
fn assert_clean(hits: &[Option<TraceHit>]) {
    for h in hits.iter().flatten() {
        assert!(
            h.t.is_finite() && h.t > 0.0 && h.u.is_finite() && h.v.is_finite(),
            "{h:?}"
        );
    }
}

#[test]
fn pbrt_needle_triangle_is_never_hit() {
    // pbrt-v4's degenerate "needle": all three vertices share x and z.
    let needle = tri(
        [-1113.45459, -79.049614, -56.2431908],
        [-1113.45459, -87.0922699, -56.2431908],
        [-1113.45459, -79.2090149, -56.2431908],
    );
    let origin = DVec3::new(-1081.47925, 99.9999542, 87.7701111);
    let d = DVec3::new(-32.1072998, -183.355865, -144.607635);
    let ray = TraceRay {
        origin,
        dir: d.normalize(),
    };
    for t in all_tests() {
        let hits = trace_with(t, &scene_with(vec![needle.clone()], origin), &[ray]);
        // Within the segment t < 0.9999 of the unnormalised direction.
        if let Some(h) = hits[0] {
            assert!(h.t as f64 >= 0.9999 * d.length(), "{t:?}: false hit {h:?}");
        }
        assert_clean(&hits);
    }
}

#[test]
fn degenerate_triangles_grazing_rays_and_signed_zeros() {
    let objects = vec![
        tri([0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]), // a point
        tri([1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]), // repeated vertex
        tri([2.0, 0.0, 0.0], [2.0, 1.0, 0.0], [2.0, 2.0, 0.0]), // collinear
    ];
    let mut rays = Vec::new();
    // Straight at the degenerate ones, with ±0 direction components.
    for x in [0.0, 1.0, 2.0] {
        for y in [0.0, 0.5, 1.0] {
            for dir in [
                DVec3::new(0.0, 0.0, -1.0),
                DVec3::new(-0.0, -0.0, -1.0),
                DVec3::new(0.0, -0.0, 1.0),
            ] {
                rays.push(TraceRay {
                    origin: DVec3::new(x, y, 5.0 * -dir.z),
                    dir,
                });
            }
        }
    }
    for t in all_tests() {
        let hits = trace_with(
            t,
            &scene_with(objects.clone(), DVec3::new(0.0, 0.0, 10.0)),
            &rays,
        );
        assert!(
            hits.iter().all(|h| h.is_none()),
            "{t:?}: a degenerate triangle was hit: {hits:?}"
        );
    }
    // Grazing: rays in the plane of a proper triangle, and rays starting on it.
    let flat = tri([-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]);
    let mut rays = Vec::new();
    for k in 0..64 {
        let a = k as f64 / 64.0 * std::f64::consts::TAU;
        rays.push(TraceRay {
            origin: DVec3::new(-3.0 * a.cos(), -3.0 * a.sin(), 0.0),
            dir: DVec3::new(a.cos(), a.sin(), 0.0),
        });
        rays.push(TraceRay {
            origin: DVec3::new(0.0, 0.0, 0.0),
            dir: DVec3::new(a.cos(), a.sin(), 0.0),
        });
        // Starting on the surface and leaving it.
        rays.push(TraceRay {
            origin: DVec3::new(0.1, 0.1, 0.0),
            dir: DVec3::new(a.cos() * 0.6, a.sin() * 0.6, 0.8),
        });
    }
    for t in all_tests() {
        let hits = trace_with(
            t,
            &scene_with(vec![flat.clone()], DVec3::new(0.0, 0.0, 10.0)),
            &rays,
        );
        assert_clean(&hits);
        assert!(
            hits.iter().all(|h| h.is_none()),
            "{t:?}: in-plane or leaving ray hit: {hits:?}"
        );
    }
}
