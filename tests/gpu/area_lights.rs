//! Area lights and sampling, checked against geometry and analytic values
//! computed here: Lambert's polygon form factor, the penumbra width of a
//! straight edge, and determinism of the sample pattern.

use crate::support;

use std::f64::consts::PI;

use glam::{DVec3, Vec3};
use penumbra::render::{KernelOptions, Sampler, Sampling};
use penumbra::scene::{
    Camera, Light, LightKind, Object, Phong, Plane, Scene, Shader, Shape, Triangle,
};

/// World point (x, 0, z) seen at the centre of pixel (i, j) of `top_down`.
fn pixel_point(half: f64, px: u32, i: u32, j: u32) -> DVec3 {
    let x = ((i as f64 + 0.5) / px as f64 * 2.0 - 1.0) * half;
    let z = ((j as f64 + 0.5) / px as f64 * 2.0 - 1.0) * half;
    DVec3::new(x, 0.0, z)
}

/// A white Lambert plane y = 0 under `lights`.
fn lambert_plane(camera: Camera, lights: Vec<Light>) -> Scene {
    Scene {
        textures: vec![],
        camera,
        background: Vec3::ZERO,
        shaders: vec![white_lambert()],
        objects: vec![Object {
            maps: Default::default(),
            shape: Shape::Plane(Plane {
                point: DVec3::ZERO,
                normal: DVec3::Y,
            }),
            shader: 0,
        }],
        lights,
    }
}

fn white_lambert() -> Shader {
    Shader::Phong(Phong {
        textures: Default::default(),
        ambient: Vec3::ZERO,
        diffuse: Vec3::ONE,
        specular: Vec3::ZERO,
        shininess: 1.0,
    })
}

fn rect(corner: DVec3, edge1: DVec3, edge2: DVec3, samples: u32) -> Light {
    Light {
        kind: LightKind::Rect {
            corner,
            edge1,
            edge2,
            samples,
        },
        intensity: 1.0,
        ambient: Vec3::ZERO,
        diffuse: Vec3::ONE,
        specular: Vec3::ZERO,
    }
}

/// Lambert's formula for the form factor from a differential area at `p`
/// with normal `n` to a polygon: F = 1/(2π) Σ βᵢ n·ĝᵢ, βᵢ the angle the edge
/// subtends and ĝᵢ the unit normal of the plane through p and the edge.
fn form_factor(p: DVec3, n: DVec3, polygon: &[DVec3]) -> f64 {
    let mut sum = 0.0;
    for k in 0..polygon.len() {
        let a = (polygon[k] - p).normalize();
        let b = (polygon[(k + 1) % polygon.len()] - p).normalize();
        let beta = a.dot(b).clamp(-1.0, 1.0).acos();
        sum += beta * n.dot(a.cross(b).normalize());
    }
    (sum / (2.0 * PI)).abs()
}

/// RMS relative error over the image against π·F/A (unit light over a
/// white Lambert plane: N point lights of 1/N weighted by the emitter cosine
/// converge to (1/A)∫cosθₑcosθᵣ/r² dA = πF/A).
fn convergence_error(samples: u32, sampler: Sampler) -> f64 {
    let (half, px) = (1.0, 24);
    let corner = DVec3::new(-0.5, 1.0, -0.5);
    let (e1, e2) = (DVec3::X, DVec3::Z); // e1 × e2 = −Y: emits downwards
    let scene = lambert_plane(
        support::top_down(half, px),
        vec![rect(corner, e1, e2, samples)],
    );
    let kernel = KernelOptions {
        sampler,
        ..Default::default()
    };
    let frame = support::render_with(&scene, kernel, Sampling::default());
    let polygon = [corner, corner + e1, corner + e1 + e2, corner + e2];
    let mut sq = 0.0;
    for j in 0..px {
        for i in 0..px {
            let want = PI * form_factor(pixel_point(half, px, i, j), DVec3::Y, &polygon);
            let got = frame.image.at(i, j)[0] as f64;
            sq += ((got - want) / want).powi(2);
        }
    }
    (sq / (px * px) as f64).sqrt()
}

/// Least-squares slope of log(error) against log(samples).
fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (xs, ys): (Vec<f64>, Vec<f64>) = points.iter().map(|(s, e)| (s.ln(), e.ln())).unzip();
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let num: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let den: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    num / den
}

#[test]
fn rect_light_converges_to_lamberts_form_factor() {
    let counts = [4u32, 16, 64, 256, 1024];
    let mut random = Vec::new();
    let mut stratified = Vec::new();
    for &n in &counts {
        random.push((n as f64, convergence_error(n, Sampler::Random)));
        stratified.push((n as f64, convergence_error(n, Sampler::Stratified)));
    }
    eprintln!("random {random:?}\nstratified {stratified:?}");
    let (sr, ss) = (slope(&random), slope(&stratified));
    eprintln!("slopes: random {sr:.3}, stratified {ss:.3}");
    // Independent samples: error ∝ N^(−1/2).
    assert!((-0.65..=-0.35).contains(&sr), "random slope {sr}");
    // Low-discrepancy samples of a smooth integrand converge clearly faster.
    assert!(ss < -0.75, "stratified slope {ss}");
    assert!(
        stratified[4].1 < random[4].1 / 4.0,
        "stratified {:?} vs random {:?}",
        stratified[4],
        random[4]
    );
    // And the limit is right: at 1024 stratified samples within 0.5 %.
    assert!(stratified[4].1 < 5e-3, "{:?}", stratified[4]);
}

/// A long rectangular light of width `w` at height `big_h` over an occluding
/// half-plane x < 0 at height `h`: the penumbra on the ground runs from
/// x = −(w/2)·h/(H−h) to +(w/2)·h/(H−h).
fn penumbra_scene(with_occluder: bool) -> Scene {
    let (w, big_h, h, len) = (2.0, 4.0, 2.0, 40.0);
    let mut objects = vec![Object {
        maps: Default::default(),
        shape: Shape::Plane(Plane {
            point: DVec3::ZERO,
            normal: DVec3::Y,
        }),
        shader: 0,
    }];
    if with_occluder {
        let (a, b, c, d) = (
            DVec3::new(-100.0, h, -100.0),
            DVec3::new(0.0, h, -100.0),
            DVec3::new(0.0, h, 100.0),
            DVec3::new(-100.0, h, 100.0),
        );
        objects.push(Object {
            maps: Default::default(),
            shape: Shape::Triangle(Triangle {
                vertices: [a, b, c],
            }),
            shader: 0,
        });
        objects.push(Object {
            maps: Default::default(),
            shape: Shape::Triangle(Triangle {
                vertices: [a, c, d],
            }),
            shader: 0,
        });
    }
    Scene {
        textures: vec![],
        camera: support::top_down(2.0, 200),
        background: Vec3::ZERO,
        shaders: vec![white_lambert()],
        objects,
        // edge1 × edge2 = (w,0,0) × (0,0,len) = (0, −w·len, 0): emits downwards.
        lights: vec![rect(
            DVec3::new(-w / 2.0, big_h, -len / 2.0),
            DVec3::new(w, 0.0, 0.0),
            DVec3::new(0.0, 0.0, len),
            1024,
        )],
    }
}

#[test]
fn penumbra_rises_monotonically_and_has_the_geometric_width() {
    let sampling = Sampling {
        spp: 4,
        ..Default::default()
    };
    let shadowed = support::render_with(&penumbra_scene(true), KernelOptions::default(), sampling);
    let free = support::render_with(&penumbra_scene(false), KernelOptions::default(), sampling);
    let row = 100; // z ≈ 0
    let v: Vec<f64> = (0..200)
        .map(|i| shadowed.image.at(i, row)[0] as f64)
        .collect();
    let f: Vec<f64> = (0..200).map(|i| free.image.at(i, row)[0] as f64).collect();
    let x = |i: usize| pixel_point(2.0, 200, i as u32, row).x;
    // Umbra: no light at all; fully lit: equal to the unoccluded render.
    let umbra_end = (0..200).rposition(|i| v[i] == 0.0).expect("an umbra");
    let lit_start = (0..200)
        .position(|i| (v[i] - f[i]).abs() <= 1e-3 * f[i])
        .expect("a lit region");
    // (w/2)·h/(H−h) = 1 · 2 / 2 = 1: the penumbra spans x in [−1, 1], 100 pixels.
    let pixel = 4.0 / 200.0;
    assert!(
        (x(umbra_end) - -1.0).abs() <= 2.0 * pixel,
        "umbra ends at x = {}",
        x(umbra_end)
    );
    assert!(
        (x(lit_start) - 1.0).abs() <= 2.0 * pixel,
        "full light starts at x = {}",
        x(lit_start)
    );
    for i in umbra_end..lit_start {
        assert!(
            v[i + 1] > v[i],
            "not rising at x = {}: {} then {}",
            x(i),
            v[i],
            v[i + 1]
        );
    }
}

#[test]
fn same_seed_same_image_other_seed_other_image() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/area_lights.json");
    let mut scene = support::load(&path);
    scene.camera.width = 96;
    scene.camera.height = 54;
    for l in &mut scene.lights {
        l.kind.set_samples(4);
    }
    let s = |seed| Sampling {
        spp: 3,
        seed,
        time_budget: None,
    };
    let a = support::render_with(&scene, KernelOptions::default(), s(0));
    let b = support::render_with(&scene, KernelOptions::default(), s(0));
    let c = support::render_with(&scene, KernelOptions::default(), s(1));
    let bits = |f: &penumbra::render::Frame| {
        f.image
            .pixels
            .iter()
            .flatten()
            .map(|x| x.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&a), bits(&b), "same seed, same bytes");
    assert_ne!(bits(&a), bits(&c), "another seed changes the image");
    assert_eq!(a.stats.passes, 3);
}

#[test]
fn time_budget_stops_after_the_pass_in_flight() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/area_lights.json");
    let mut scene = support::load(&path);
    scene.camera.width = 64;
    scene.camera.height = 36;
    let sampling = Sampling {
        spp: 10_000,
        seed: 0,
        time_budget: Some(std::time::Duration::from_millis(1)),
    };
    let frame = support::render_with(&scene, KernelOptions::default(), sampling);
    assert!(
        frame.stats.passes >= 1 && frame.stats.passes < 10_000,
        "{} passes",
        frame.stats.passes
    );
    // The image is the mean of the passes done: bounded like a single pass.
    assert!(frame
        .image
        .pixels
        .iter()
        .all(|p| p.iter().all(|c| c.is_finite()) && p[3] <= 1.0));
}

#[test]
fn spp_one_is_the_pixel_centre_image() {
    // Area-light-free scenes with one sample per pixel render exactly as the
    // core renderer always did (the sampling code is not compiled in).
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase.json");
    let mut scene = support::load(&path);
    scene.camera.width = 120;
    scene.camera.height = 68;
    assert!(!scene.features().area_lights);
    let one = support::render_with(&scene, KernelOptions::default(), Sampling::default());
    let plain = support::render(&scene);
    assert_eq!(one.image, plain.image);
    // Several samples per pixel average sub-pixel positions: edges change.
    let four = support::render_with(
        &scene,
        KernelOptions::default(),
        Sampling {
            spp: 4,
            ..Default::default()
        },
    );
    assert_ne!(four.image, one.image);
    assert_eq!(four.stats.primary_rays, 4 * 120 * 68);
}

#[test]
fn sphere_light_far_away_acts_like_a_point_light() {
    // N points of I/N on a small sphere converge to a point light of I at its
    // centre (no emitter cosine for spheres).
    let mut scene = lambert_plane(
        support::top_down(1.0, 16),
        vec![Light {
            kind: LightKind::Sphere {
                center: DVec3::new(0.3, 3.0, -0.2),
                radius: 0.01,
                samples: 64,
            },
            intensity: 2.0,
            ambient: Vec3::ZERO,
            diffuse: Vec3::ONE,
            specular: Vec3::ZERO,
        }],
    );
    let sphere = support::render_with(&scene, KernelOptions::default(), Sampling::default());
    scene.lights[0].kind = LightKind::Point {
        position: DVec3::new(0.3, 3.0, -0.2),
    };
    let point = support::render(&scene);
    for (a, b) in sphere.image.pixels.iter().zip(&point.image.pixels) {
        assert!((a[0] - b[0]).abs() <= 1e-3 * b[0], "{} vs {}", a[0], b[0]);
    }
}

/// The environment (docs/materials.md, "Environment"): radiance
/// `I·g(ω·up)`, `g(u) = a + b·u`, from every direction, unshadowed. A white
/// Lambert surface (Phong, `k_d` = 1: radiance `k_d·E` with no 1/π) with unit
/// normal `n` receives `E = ∫ g(ω·up)·max(0, ω·n) dω = π·a + (2π/3)·b·(n·up)`
/// (∫ over the hemisphere of `ω·n` is π, of `ω (ω·n)` is (2π/3)·n). The plane
/// is tilted away from up so that both terms count; an occluder right above
/// it must not darken it (no shadow rays).
///
/// Each pixel is a Monte Carlo estimate from `N` = samples × spp directions
/// of the environment's mixture (density `p`, docs/materials.md): it lies
/// within 4 standard deviations `σ/√N` of `E` (`σ²` = E[X²] − E²,
/// `X = g·max(0, ω·n)/p(ω)`, E[X²] = ∫ g² cos²/p dω over the hemisphere,
/// bounded above by putting only the mixture's uniform and cosine parts in
/// `p`: its Phong lobes only add density), and the image's mean within
/// 4σ/√(N·pixels).
#[test]
fn environment_light_on_a_plane() {
    use penumbra::scene::ENVIRONMENT_GRADIENT;
    let (a, b) = ENVIRONMENT_GRADIENT;
    let up = DVec3::new(0.0, 1.0, 0.0);
    let n = DVec3::new(0.6, 0.8, 0.0);
    let intensity = 1.5f32;
    let (samples, spp) = (1024u32, 4u32);
    let mut scene = lambert_plane(
        support::top_down(1.0, 16),
        vec![Light {
            kind: LightKind::Environment { up, samples },
            intensity,
            ambient: Vec3::ZERO,
            diffuse: Vec3::ONE,
            specular: Vec3::ZERO,
        }],
    );
    scene.objects[0].shape = Shape::Plane(Plane {
        point: DVec3::ZERO,
        normal: n,
    });
    // A triangle above the whole view, facing the plane: it would block
    // most of the sky if the environment were shadowed.
    scene.objects.push(Object {
        maps: Default::default(),
        shape: Shape::Triangle(Triangle {
            vertices: [
                DVec3::new(-20.0, 3.0, -20.0),
                DVec3::new(20.0, 3.0, -20.0),
                DVec3::new(0.0, 3.0, 20.0),
            ],
        }),
        shader: 0,
    });
    scene.camera.position = DVec3::new(0.0, 2.0, 0.0);
    let c = n.dot(up);
    let i0 = intensity as f64;
    let expected = i0 * (PI * a + 2.0 * PI / 3.0 * b * c);
    let (wu, wc) = (
        penumbra::scene::ENVIRONMENT_MIXTURE.uniform,
        penumbra::scene::ENVIRONMENT_MIXTURE.cosine,
    );
    // E[X²] ≤ ∫_hemi (I·(a + b·ω·up))² (ω·n)² / p dω, by the midpoint rule
    // on the hemisphere around n (uniform in cos θ and φ, dω = dcos dφ).
    let (t, s2) = (n.cross(DVec3::Z).normalize(), DVec3::Z);
    let m = 400;
    let mut second = 0.0;
    for i in 0..m {
        let cos = (i as f64 + 0.5) / m as f64; // uniform in cos: dω = dcos dφ
        let sin = (1.0 - cos * cos).sqrt();
        for j in 0..m {
            let phi = (j as f64 + 0.5) / m as f64 * 2.0 * PI;
            let w = n * cos + t * (sin * phi.cos()) + s2 * (sin * phi.sin());
            let g = i0 * (a + b * w.dot(up));
            second += g * g * cos * cos / (wu / (4.0 * PI) + wc * cos / PI);
        }
    }
    second *= 2.0 * PI / (m * m) as f64;
    let sigma = (second - expected * expected).sqrt();
    let count = (samples * spp) as f64;
    let frame = support::render_with(
        &scene,
        KernelOptions::default(),
        Sampling {
            spp,
            seed: 0,
            time_budget: None,
        },
    );
    let pixels = &frame.image.pixels;
    let mut sum = 0.0;
    for p in pixels {
        let v = p[0] as f64;
        assert!(
            (v - expected).abs() <= 4.0 * sigma / count.sqrt(),
            "{v} vs {expected} (σ {sigma})"
        );
        sum += v;
    }
    let mean = sum / pixels.len() as f64;
    let bound = 4.0 * sigma / (count * pixels.len() as f64).sqrt();
    assert!(
        (mean - expected).abs() <= bound,
        "mean {mean} vs {expected} ± {bound}"
    );
}
