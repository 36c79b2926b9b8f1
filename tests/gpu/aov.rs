//! Arbitrary output variables (depth, normal, uv, ids) against values
//! computed here in f64, and their OpenEXR channels.

use crate::support;

use glam::{DMat3, DVec3, Vec3};
use penumbra::output::{write_exr_with_aovs, AovSet};
use penumbra::render::Sampling;
use penumbra::scene::{
    Camera, Mesh, Object, Phong, Plane, Projection, Scene, Shader, Shape, Sphere,
};

fn scene() -> Scene {
    let eye = DVec3::new(0.3, 4.0, 6.0);
    Scene {
        textures: vec![],
        camera: Camera {
            position: eye,
            orientation: Camera::look_at(eye, DVec3::new(0.0, 1.6, -2.0), DVec3::Y).unwrap(),
            projection: Projection::Perspective { vfov_deg: 50.0 },
            width: 120,
            height: 90,
        },
        background: Vec3::ZERO,
        shaders: vec![Shader::Phong(Phong {
            textures: Default::default(),
            ambient: Vec3::ZERO,
            diffuse: Vec3::ONE,
            specular: Vec3::ZERO,
            shininess: 1.0,
        })],
        objects: vec![
            // 0: the floor.
            Object {
                maps: Default::default(),
                shape: Shape::Plane(Plane {
                    point: DVec3::ZERO,
                    normal: DVec3::Y,
                }),
                shader: 0,
            },
            // 1: a sphere.
            Object {
                maps: Default::default(),
                shape: Shape::Sphere(Sphere {
                    center: DVec3::new(-1.5, 1.0, 0.0),
                    radius: 1.0,
                }),
                shader: 0,
            },
            // 2: a tilted quad of two triangles, as a mesh.
            Object {
                maps: Default::default(),
                shape: Shape::Mesh(Mesh {
                    uvs: vec![],
                    colours: None,
                    tangents: None,
                    positions: vec![
                        DVec3::new(0.5, 0.5, -1.0),
                        DVec3::new(2.5, 0.5, -1.0),
                        DVec3::new(2.5, 2.0, -2.0),
                        DVec3::new(0.5, 2.0, -2.0),
                    ],
                    normals: None,
                    indices: vec![[0, 1, 2], [0, 2, 3]],
                }),
                shader: 0,
            },
        ],
        lights: vec![],
    }
}

/// The pixel centre's primary ray, in f64, from the camera definition.
fn ray(c: &Camera, x: u32, y: u32) -> DVec3 {
    let (hw, hh) = c.half_extent();
    let sx = ((x as f64 + 0.5) / c.width as f64 * 2.0 - 1.0) * hw;
    let sy = (1.0 - (y as f64 + 0.5) / c.height as f64 * 2.0) * hh;
    let o: DMat3 = c.orientation;
    (o.x_axis * sx + o.y_axis * sy - o.z_axis).normalize()
}

#[test]
fn depth_normal_uv_and_ids_match_the_geometry() {
    let s = scene();
    let (frame, aovs) = {
        let mut r = support::renderer();
        let up = r.upload(&s).unwrap();
        r.render(
            &up,
            penumbra::render::RenderRequest::with_aovs(120, 90, &Sampling::default(), &mut |_| {}),
        )
        .map(|r| (r.frame, r.aovs.unwrap_or_default()))
        .unwrap()
    };
    let c = &s.camera;
    let Shape::Sphere(sphere) = s.objects[1].shape else {
        unreachable!()
    };
    let Shape::Mesh(quad) = &s.objects[2].shape else {
        unreachable!()
    };
    let (mut counted, mut worst_depth) = ([0usize; 4], 0f64);
    for y in 0..90 {
        for x in 0..120 {
            let i = (y * 120 + x) as usize;
            let d = ray(c, x, y);
            // Nearest of the three objects, in f64.
            let mut best: Option<(f64, u32, u32, DVec3, [f64; 2])> = None;
            let mut consider = |t: f64, obj: u32, prim: u32, n: DVec3, uv: [f64; 2]| {
                if best.is_none_or(|b| t < b.0) {
                    best = Some((t, obj, prim, n, uv));
                }
            };
            if let Some(t) = (Plane {
                point: DVec3::ZERO,
                normal: DVec3::Y,
            })
            .intersect(c.position, d)
            {
                consider(t, 0, 0, DVec3::Y, [0.0; 2]);
            }
            if let Some(t) = sphere.intersect(c.position, d) {
                consider(t, 1, 0, sphere.normal_at(c.position + d * t), [0.0; 2]);
            }
            for k in 0..2 {
                let tri = quad.triangle(k);
                if let Some(h) = tri.intersect(c.position, d) {
                    consider(
                        h.t,
                        2,
                        k as u32,
                        tri.geometric_normal().normalize(),
                        [h.u, h.v],
                    );
                }
            }
            let Some((t, obj, prim, n, uv)) = best else {
                assert_eq!(aovs.depth[i], f32::INFINITY, "miss at {x},{y}");
                assert_eq!((aovs.object[i], aovs.primitive[i]), (u32::MAX, u32::MAX));
                assert_eq!(frame.image.pixels[i][3], 0.0);
                counted[3] += 1;
                continue;
            };
            // Skip pixel centres within a hair of an object's silhouette or
            // of the quad's diagonal, where f32 may pick the neighbour.
            let near_edge = (obj == 2
                && (uv[0] < 1e-3 || uv[1] < 1e-3 || uv[0] + uv[1] > 1.0 - 1e-3))
                || (obj == 1 && n.dot(d).abs() < 1e-2);
            if near_edge || aovs.object[i] != obj {
                assert!(
                    near_edge,
                    "object at {x},{y}: got {} want {obj}",
                    aovs.object[i]
                );
                continue;
            }
            counted[obj as usize] += 1;
            assert_eq!(aovs.primitive[i], prim, "primitive at {x},{y}");
            // Depth. The data are camera-relative f32 values (eye subtracted in
            // f64), each within half an ulp (2⁻²⁴ relative); ray setup and
            // intersection add a few dozen roundings of that size (64 · 2⁻²⁴ ≈
            // 3.8e-6), which the angle of incidence amplifies by 1/|n·d|.
            let rel = (aovs.depth[i] as f64 - t).abs() / t;
            let bound = 64.0 * 2f64.powi(-24) / n.dot(d).abs();
            assert!(
                rel <= bound,
                "depth at {x},{y}: relative error {rel:e} > {bound:e}"
            );
            worst_depth = worst_depth.max(rel);
            // The normal faces the viewer.
            let n = if n.dot(d) > 0.0 { -n } else { n };
            let got = DVec3::from_array(aovs.normal[i].map(f64::from));
            assert!((got - n).length() < 1e-5, "normal at {x},{y}: {got} vs {n}");
            if obj == 2 {
                let got = aovs.uv[i];
                assert!(
                    (got[0] as f64 - uv[0]).abs() < 1e-4 && (got[1] as f64 - uv[1]).abs() < 1e-4,
                    "uv at {x},{y}: {got:?} vs {uv:?}"
                );
            } else {
                assert_eq!(aovs.uv[i], [0.0, 0.0]);
            }
        }
    }
    eprintln!("pixels per object {counted:?}, worst relative depth error {worst_depth:e}");
    assert!(counted.iter().all(|&n| n > 300), "{counted:?}");
}

#[test]
fn aovs_land_in_exr_channels() {
    let s = scene();
    let (frame, aovs) = {
        let mut r = support::renderer();
        let up = r.upload(&s).unwrap();
        r.render(
            &up,
            penumbra::render::RenderRequest::with_aovs(120, 90, &Sampling::default(), &mut |_| {}),
        )
        .map(|r| (r.frame, r.aovs.unwrap_or_default()))
        .unwrap()
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("aov.exr");
    let all = AovSet {
        depth: true,
        normal: true,
        uv: true,
        id: true,
    };
    write_exr_with_aovs(&path, &frame.image, &aovs, all).unwrap();
    let image = exr::prelude::read_all_flat_layers_from_file(&path).unwrap();
    let layer = &image.layer_data[0];
    let channel = |name: &str| {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)
            .unwrap_or_else(|| panic!("channel {name} missing"))
    };
    use exr::prelude::FlatSamples;
    let FlatSamples::F32(z) = &channel("Z").sample_data else {
        panic!("Z is f32")
    };
    assert_eq!(z, &aovs.depth);
    let FlatSamples::F32(r) = &channel("R").sample_data else {
        panic!("R is f32")
    };
    assert!(r.iter().zip(&frame.image.pixels).all(|(a, p)| *a == p[0]));
    let FlatSamples::U32(ids) = &channel("id.object").sample_data else {
        panic!("id is u32")
    };
    assert_eq!(ids, &aovs.object);
    for name in [
        "G",
        "B",
        "N.X",
        "N.Y",
        "N.Z",
        "uv.U",
        "uv.V",
        "id.primitive",
    ] {
        channel(name);
    }
    // Only the channels asked for.
    let path = dir.path().join("depth.exr");
    write_exr_with_aovs(
        &path,
        &frame.image,
        &aovs,
        AovSet {
            depth: true,
            ..Default::default()
        },
    )
    .unwrap();
    let image = exr::prelude::read_all_flat_layers_from_file(&path).unwrap();
    assert_eq!(image.layer_data[0].channel_data.list.len(), 4);
}
