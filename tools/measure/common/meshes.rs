//! The benchmark's scenes: the bunny scene as committed, and variants of it
//! with the bunny replaced by procedural meshes of any size (same camera,
//! light, ground and materials), and the bunny scene textured.

use std::collections::HashMap;
use std::path::Path;

use glam::{DVec2, DVec3};
use penumbra::loaders::{self, LoadOptions};
use penumbra::scene::{
    AlphaMode, Light, LightKind, Mesh, Scene, Shader, Shape, SurfaceMaps, Texture, TextureRef,
};

/// Loads `scenes/bunny_scene.glb` with its materials as the seminar's Phong
/// (`--gltf-materials phong`): the benchmark's scene as its figures have
/// always been measured (and as the plain Rust port renders it).
/// `materials_bench` compares it with glTF's own model.
pub fn bunny_scene(root: &Path) -> anyhow::Result<Scene> {
    let path = root.join("scenes/bunny_scene.glb");
    let opts = LoadOptions {
        gltf_materials: loaders::GltfMaterials::Phong,
        ..Default::default()
    };
    Ok(loaders::load_scene(&path, &opts)?.scene)
}

/// The bunny's mesh (the object with more than two triangles).
pub fn bunny_mesh(scene: &mut Scene) -> &mut Mesh {
    scene
        .objects
        .iter_mut()
        .find_map(|o| match &mut o.shape {
            Shape::Mesh(m) if m.indices.len() > 2 => Some(m),
            _ => None,
        })
        .expect("the bunny scene has a bunny")
}

/// Area-weighted vertex normals.
pub fn vertex_normals(positions: &[DVec3], indices: &[[u32; 3]]) -> Vec<DVec3> {
    let mut n = vec![DVec3::ZERO; positions.len()];
    for t in indices {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let face = (b - a).cross(c - a);
        for &i in t {
            n[i as usize] += face;
        }
    }
    n.into_iter()
        .map(|v| v.try_normalize().unwrap_or(DVec3::Y))
        .collect()
}

/// One level of midpoint subdivision (each triangle into four) with the new
/// edge vertices displaced by Phong tessellation (Boubekeur and Alexa 2008,
/// shape factor 3/4): the midpoint is projected onto the tangent planes of
/// both end vertices and the average taken, which bulges flat edges out to
/// the curved surface the vertex normals describe. Shared edges get one new
/// vertex, so the mesh stays watertight.
pub fn subdivide(mesh: &Mesh) -> Mesh {
    let normals = mesh
        .normals
        .clone()
        .unwrap_or_else(|| vertex_normals(&mesh.positions, &mesh.indices));
    let mut positions = mesh.positions.clone();
    let mut new_normals = normals.clone();
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    let mut midpoint = |a: u32, b: u32, positions: &mut Vec<DVec3>, nn: &mut Vec<DVec3>| {
        let key = (a.min(b), a.max(b));
        *edges.entry(key).or_insert_with(|| {
            let (pa, pb) = (positions[a as usize], positions[b as usize]);
            let (na, nb) = (normals[a as usize], normals[b as usize]);
            let m = (pa + pb) * 0.5;
            let project = |p: DVec3, q: DVec3, n: DVec3| p - (p - q).dot(n) * n;
            let phong = (project(m, pa, na) + project(m, pb, nb)) * 0.5;
            positions.push(m * 0.25 + phong * 0.75);
            nn.push((na + nb).try_normalize().unwrap_or(na));
            positions.len() as u32 - 1
        })
    };
    let mut indices = Vec::with_capacity(mesh.indices.len() * 4);
    for &[a, b, c] in &mesh.indices {
        let ab = midpoint(a, b, &mut positions, &mut new_normals);
        let bc = midpoint(b, c, &mut positions, &mut new_normals);
        let ca = midpoint(c, a, &mut positions, &mut new_normals);
        indices.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    Mesh {
        uvs: vec![],
        colours: None,
        tangents: None,
        positions,
        normals: Some(new_normals),
        indices,
    }
}

/// A bumpy sphere: a latitude/longitude grid of `rings` rings and
/// `2·rings` meridians, radius modulated by a few sine waves, with vertex
/// normals. At the poles each grid cell is one triangle, elsewhere two:
/// 4·rings·(rings − 1) triangles, none degenerate.
pub fn bumpy_sphere(rings: u32, centre: DVec3, radius: f64) -> Mesh {
    let (n, m) = (rings, 2 * rings);
    let mut positions = Vec::with_capacity(((n - 1) * m + 2) as usize);
    let surface = |theta: f64, phi: f64| {
        let r = radius
            * (1.0 + 0.06 * (7.0 * theta).sin() * (5.0 * phi).sin() + 0.03 * (17.0 * phi).cos());
        centre
            + r * DVec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            )
    };
    positions.push(surface(0.0, 0.0)); // north pole: vertex 0
    for i in 1..n {
        let theta = std::f64::consts::PI * i as f64 / n as f64;
        for j in 0..m {
            let phi = std::f64::consts::TAU * j as f64 / m as f64;
            positions.push(surface(theta, phi));
        }
    }
    positions.push(surface(std::f64::consts::PI, 0.0)); // south pole
    let south = positions.len() as u32 - 1;
    let ring = |i: u32, j: u32| 1 + (i - 1) * m + j % m;
    let mut indices = Vec::with_capacity((4 * n * (n - 1)) as usize);
    for j in 0..m {
        indices.push([0, ring(1, j + 1), ring(1, j)]);
        indices.push([south, ring(n - 1, j), ring(n - 1, j + 1)]);
    }
    for i in 1..n - 1 {
        for j in 0..m {
            let (a, b) = (ring(i, j), ring(i, j + 1));
            let (c, d) = (ring(i + 1, j), ring(i + 1, j + 1));
            indices.push([a, b, d]);
            indices.push([a, d, c]);
        }
    }
    let normals = vertex_normals(&positions, &indices);
    Mesh {
        uvs: vec![],
        colours: None,
        tangents: None,
        positions,
        normals: Some(normals),
        indices,
    }
}

/// The number of rings whose bumpy sphere has about `triangles` triangles.
pub fn rings_for(triangles: u64) -> u32 {
    ((1.0 + (1.0 + triangles as f64).sqrt()) / 2.0)
        .round()
        .max(3.0) as u32
}

/// The bunny scene with the bunny replaced by a bumpy sphere of about
/// `triangles` triangles, standing on the ground where the bunny stood and
/// about as large.
pub fn sphere_scene(bunny: &Scene, triangles: u64) -> Scene {
    let mut scene = bunny.clone();
    let mesh = bunny_mesh(&mut scene);
    let (lo, hi) = mesh.bounds().expect("bunny has vertices");
    let extent = hi - lo;
    let radius = (extent.x + extent.y + extent.z) / 6.0;
    let centre = DVec3::new(
        (lo.x + hi.x) / 2.0,
        lo.y + radius * 1.1,
        (lo.z + hi.z) / 2.0,
    );
    *mesh = bumpy_sphere(rings_for(triangles), centre, radius);
    scene
}

/// The bunny scene with the bunny subdivided `levels` times.
pub fn subdivided_bunny(bunny: &Scene, levels: u32) -> Scene {
    let mut scene = bunny.clone();
    let mesh = bunny_mesh(&mut scene);
    for _ in 0..levels {
        *mesh = subdivide(mesh);
    }
    scene
}

/// The bunny scene lit by `count` directional lights: the scene's light and
/// copies of it turned about the vertical axis in equal steps, each with
/// 1/count of the intensity (the image keeps its brightness).
pub fn with_lights(bunny: &Scene, count: usize) -> Scene {
    let mut scene = bunny.clone();
    let base: Light = scene.lights[0];
    let LightKind::Directional { direction } = base.kind else {
        panic!("the bunny scene's light is directional");
    };
    scene.lights = (0..count)
        .map(|k| {
            let angle = std::f64::consts::TAU * k as f64 / count as f64;
            let turned = glam::DQuat::from_rotation_y(angle) * direction;
            Light {
                kind: LightKind::Directional { direction: turned },
                intensity: base.intensity / count as f32,
                ..base
            }
        })
        .collect();
    scene
}

/// A procedural RGBA8 texture of `side`² texels: `cells`² squares of two
/// colours with a thin dark grid, and alpha cut in stripes where `stripes`
/// (0 or 255), as a colour (sRGB) texture.
fn pattern(side: u32, cells: u32, a: [u8; 3], b: [u8; 3], stripes: bool, label: &str) -> Texture {
    let cell = side / cells;
    let texels = (0..side * side)
        .map(|i| {
            let (x, y) = (i % side, i / side);
            let c = if (x / cell + y / cell).is_multiple_of(2) {
                a
            } else {
                b
            };
            let grid = x % cell == 0 || y % cell == 0;
            let rgb = if grid { c.map(|v| v / 3) } else { c };
            let alpha = if stripes && (y / (cell / 2).max(1)) % 2 == 1 {
                0
            } else {
                255
            };
            [rgb[0], rgb[1], rgb[2], alpha]
        })
        .collect();
    Texture {
        label: label.into(),
        file: None,
        width: side,
        height: side,
        texels,
        srgb: true,
    }
}

/// The bunny scene textured, for the benchmark's cost of texturing: the
/// bunny gets cylindrical texture coordinates around its vertical axis and a
/// 256² texture, the ground planar coordinates tiling a 512² texture 16
/// times, both trilinear. With `masked`, the bunny's material is a cut-out
/// (alpha MASK from the texture's stripes) as well.
pub fn textured_bunny_scene(root: &Path, masked: bool) -> anyhow::Result<Scene> {
    let mut scene = bunny_scene(root)?;
    scene.textures = vec![
        pattern(
            256,
            8,
            [200, 160, 110],
            [120, 80, 50],
            masked,
            "bunny pattern",
        ),
        pattern(
            512,
            8,
            [190, 190, 180],
            [90, 100, 110],
            false,
            "ground tiles",
        ),
    ];
    let bunny_at = scene
        .objects
        .iter()
        .position(|o| matches!(&o.shape, Shape::Mesh(m) if m.indices.len() > 2))
        .expect("the bunny scene has a bunny");
    for (i, o) in scene.objects.iter_mut().enumerate() {
        let Shape::Mesh(m) = &mut o.shape else {
            continue;
        };
        let Some((lo, hi)) = m.bounds() else { continue };
        let centre = (lo + hi) * 0.5;
        let size = (hi - lo).max(DVec3::splat(1e-9));
        let bunny = i == bunny_at;
        m.uvs = vec![m
            .positions
            .iter()
            .map(|p| {
                if bunny {
                    let d = *p - centre;
                    DVec2::new(
                        0.5 + d.z.atan2(d.x) / std::f64::consts::TAU,
                        (hi.y - p.y) / size.y,
                    )
                } else {
                    DVec2::new((p.x - lo.x) / size.x, (p.z - lo.z) / size.z)
                }
            })
            .collect()];
        let texture = if bunny { 0 } else { 1 };
        let mut use_ = TextureRef::new(texture);
        if !bunny {
            use_.transform.scale = DVec2::splat(16.0);
        }
        let Shader::Phong(mut p) = scene.shaders[o.shader].clone() else {
            anyhow::bail!("the bunny scene's materials are Phong");
        };
        p.textures.diffuse = Some(use_);
        scene.shaders.push(Shader::Phong(p));
        o.shader = scene.shaders.len() - 1;
        if bunny && masked {
            o.maps = SurfaceMaps {
                alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
                opacity_texture: Some(use_),
                ..SurfaceMaps::default()
            };
        }
    }
    scene
        .validate()
        .map_err(|e| anyhow::anyhow!("the textured bunny scene: {e:?}"))?;
    Ok(scene)
}

/// Writes `src` (a binary glTF file whose node 0 draws mesh 0, the bunny,
/// with no transform: scenes/bunny_scene.glb) to `out` with mesh 0's
/// triangles replaced by `mesh`'s, positions as the f32 the renderer
/// uploads: so that a peer that builds its scene from a .glb file renders
/// the same subdivided bunny as penumbra's in-memory `subdivided_bunny`.
pub fn write_glb_with_bunny(src: &Path, mesh: &Mesh, out: &Path) -> anyhow::Result<()> {
    use anyhow::Context as _;
    let data = std::fs::read(src).with_context(|| src.display().to_string())?;
    let word = |at: usize| -> anyhow::Result<usize> {
        let b = data.get(at..at + 4).context("a truncated .glb")?;
        Ok(u32::from_le_bytes(b.try_into().expect("4 bytes")) as usize)
    };
    anyhow::ensure!(
        data.get(..4) == Some(b"glTF".as_slice()),
        "{}: not a .glb",
        src.display()
    );
    let json_len = word(12)?;
    let mut doc: serde_json::Value = serde_json::from_slice(&data[20..20 + json_len])?;
    let bin_at = 20 + json_len;
    let bin_len = word(bin_at)?;
    let mut bin = data[bin_at + 8..bin_at + 8 + bin_len].to_vec();
    anyhow::ensure!(
        doc["nodes"][0]["mesh"] == 0
            && ["matrix", "translation", "rotation", "scale"]
                .iter()
                .all(|k| doc["nodes"][0].get(k).is_none()),
        "{}: node 0 must draw mesh 0 without a transform",
        src.display()
    );
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let positions: Vec<f32> = mesh
        .positions
        .iter()
        .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32])
        .collect();
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for p in positions.chunks_exact(3) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let indices: Vec<u32> = mesh.indices.iter().flatten().copied().collect();
    let views = doc["bufferViews"].as_array().map_or(0, Vec::len);
    let accessors = doc["accessors"].as_array().map_or(0, Vec::len);
    let mut add = |bytes: &[u8], target: u32| -> serde_json::Value {
        let view = serde_json::json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len(), "target": target});
        bin.extend_from_slice(bytes);
        view
    };
    let pos_bytes: Vec<u8> = positions.iter().flat_map(|v| v.to_le_bytes()).collect();
    let idx_bytes: Vec<u8> = indices.iter().flat_map(|v| v.to_le_bytes()).collect();
    let pos_view = add(&pos_bytes, 34962);
    let idx_view = add(&idx_bytes, 34963);
    let views_json = doc["bufferViews"]
        .as_array_mut()
        .context("no bufferViews")?;
    views_json.extend([pos_view, idx_view]);
    doc["accessors"]
        .as_array_mut()
        .context("no accessors")?
        .extend([
            serde_json::json!({"bufferView": views, "componentType": 5126, "count": mesh.positions.len(), "type": "VEC3", "min": lo, "max": hi}),
            serde_json::json!({"bufferView": views + 1, "componentType": 5125, "count": indices.len(), "type": "SCALAR"}),
        ]);
    let prim = &mut doc["meshes"][0]["primitives"][0];
    prim["attributes"] = serde_json::json!({"POSITION": accessors});
    prim["indices"] = serde_json::json!(accessors + 1);
    doc["buffers"][0]["byteLength"] = serde_json::json!(bin.len());
    let mut json = serde_json::to_vec(&doc)?;
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut glb = Vec::with_capacity(28 + json.len() + bin.len());
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&((28 + json.len() + bin.len()) as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    std::fs::write(out, glb).with_context(|| out.display().to_string())
}
