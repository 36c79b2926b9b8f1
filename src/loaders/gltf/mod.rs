//! glTF 2.0 files (`.gltf` with external or embedded buffers, `.glb`): the
//! triangle meshes, the first camera and the KHR_lights_punctual lights of the
//! default scene, with every node transform applied, and their materials as
//! Phong shaders with textures, normal maps, emission and alpha
//! ([`material`]); tangents come from TANGENT or MikkTSpace ([`tangents`]).
//!
//! The `gltf` crate parses and validates the JSON; its validation reports field
//! paths, which become [`SceneError::field`]. Buffers and accessors are read
//! here instead of by `gltf::import` and its `Reader`: `import` also decodes
//! images (failing on a missing texture) and pads buffers, which lets a short
//! one pass its length check, and the reader trusts byte ranges and strides
//! and can panic on inconsistent files. Every range is checked before a byte is
//! read, so no file content can make this module panic.

mod cameras;
mod decode;
mod draco;
mod extensions;
mod fields;
pub mod framing;
mod indices;
mod instancing;
mod material;
mod meshopt;
mod morph;
mod quantization;
mod tangents;

use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::{Path, PathBuf};

use glam::{DMat3, DMat4, DQuat, DVec2, DVec3, DVec4, Vec3, Vec4};
use gltf::accessor::{sparse::IndexType, Accessor, DataType, Dimensions};
use gltf::buffer::{Source, View};
use gltf::json::validation::{Checked, Validate};
use gltf::khr_lights_punctual::Kind;
use gltf::mesh::{Mode, Semantic};
use gltf::scene::Transform;

pub use self::cameras::{CameraChoice, PlacedCamera};
use self::quantization::Attribute;
use super::guard::Guard;
use super::{LoadOptions, Loaded};
use crate::loaders::GltfMaterials;
use crate::scene::{
    Camera, Light, LightKind, Mesh, MetallicRoughness, Object, Phong, Projection, Scene, Shader,
    Shape, SurfaceMaps, Texture, TextureId,
};
use crate::SceneError;

type Result<T> = std::result::Result<T, SceneError>;

/// One triangle mesh from the file: world-space geometry and its material.
#[derive(Clone, Debug)]
pub struct GltfMesh {
    /// Triangle list with positions, normals and tangents in world space
    /// (node transforms applied), its TEXCOORD_0/1 and COLOR_0.
    pub mesh: Mesh,
    /// Linear RGB of the material's `baseColorFactor`; `None` when the primitive has no material.
    pub base_color: Option<Vec3>,
    /// The Phong shader of its material (module [`material`]); its
    /// textures index [`GltfDocument::textures`].
    pub phong: Phong,
    /// Its material as glTF's metallic-roughness model; textures as `phong`'s.
    pub pbr: MetallicRoughness,
    /// KHR_materials_unlit: `maps.emission` is its colour; use [`UNLIT`].
    pub unlit: bool,
    /// KHR_materials_pbrSpecularGlossiness, used instead of `pbr` where given.
    pub specular_glossiness: Option<crate::scene::SpecularGlossiness>,
    /// The material's normal map, emission and alpha; textures index
    /// [`GltfDocument::textures`].
    pub maps: SurfaceMaps,
    /// Where it came from, for messages, e.g. `node 'Bunny' mesh 0 primitive 0`.
    pub name: String,
    /// Its primitive's field in the file, e.g. `meshes[0].primitives[1]`.
    pub primitive: String,
    /// Its primitive's `material` index, if it has one.
    pub material: Option<usize>,
}

/// The camera of the file, placed by its node's world transform.
#[derive(Clone, Copy, Debug)]
pub struct GltfCamera {
    /// Eye position, world units.
    pub position: DVec3,
    /// Rotation only (node scale removed): columns right, up, back; it looks along −Z.
    pub orientation: DMat3,
    /// `yfov` as a vertical field of view, or `ymag` as the orthographic half height.
    pub projection: Projection,
    /// The perspective camera's `aspectRatio`, if given.
    pub aspect_ratio: Option<f64>,
}

/// Everything penumbra uses from a glTF file.
#[derive(Clone, Debug)]
pub struct GltfDocument {
    /// One entry per triangle primitive instanced in the default scene.
    pub meshes: Vec<GltfMesh>,
    /// The first camera instanced by a node of the default scene (depth-first order).
    pub camera: Option<GltfCamera>,
    /// Every camera placed by a node of the default scene, in that order.
    pub cameras: Vec<PlacedCamera>,
    /// The KHR_lights_punctual lights instanced in the default scene.
    pub lights: Vec<Light>,
    /// Notes for the user about parts of the file that are not used; one line each.
    pub notes: Vec<String>,
    /// The `.gltf`/`.glb` itself, then every external buffer and image file read.
    pub files: Vec<PathBuf>,
    /// The decoded images that the meshes' materials use, one per (image,
    /// colour space).
    pub textures: Vec<Texture>,
}

/// Reads the file's default scene (its `scene`, else scene 0), with the
/// default limits of [`LoadOptions`].
pub fn read(path: &Path) -> Result<GltfDocument> {
    read_with(path, &Guard::new(path, &LoadOptions::default()))
}

/// [`read`] under the limits of `guard`, shared with the scene that names this file.
pub fn read_with(path: &Path, guard: &Guard) -> Result<GltfDocument> {
    read_scene(path, guard).map(|(doc, _)| doc)
}

/// `penumbra render model.glb`: the whole scene from a glTF file, with a
/// framing camera and a default light when the file has none.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Loaded> {
    let (doc, scene_index) = read_scene(path, &Guard::new(path, opts))?;
    let mut notes = doc.notes;
    if doc.meshes.iter().all(|m| m.mesh.indices.is_empty()) {
        let field = scene_index.map_or("scenes".into(), |k| format!("scenes[{k}]"));
        let message = "no triangle meshes in the default scene";
        return Err(SceneError::new(path, field, message));
    }

    // One shader per distinct shader (colour and textures), in order of
    // first use; the maps stay per object.
    let pbr = opts.gltf_materials == GltfMaterials::MetallicRoughness;
    if pbr {
        notes.retain(|n| !n.ends_with(METALLIC_ROUGHNESS_NOTE));
    }
    let mut shaders: Vec<Shader> = Vec::new();
    let mut objects = Vec::with_capacity(doc.meshes.len());
    let mut origins = Vec::with_capacity(doc.meshes.len());
    for m in doc.meshes {
        origins.push(fields::Origin {
            primitive: m.primitive,
            material: m.material,
        });
        let wanted = match (m.unlit, pbr, m.specular_glossiness) {
            (true, _, _) => Shader::Phong(UNLIT),
            (false, true, Some(sg)) => Shader::SpecularGlossiness(sg),
            (false, true, None) => Shader::MetallicRoughness(m.pbr),
            (false, false, _) => Shader::Phong(m.phong),
        };
        let shader = shaders
            .iter()
            .position(|s| *s == wanted)
            .unwrap_or_else(|| {
                shaders.push(wanted);
                shaders.len() - 1
            });
        objects.push(Object {
            maps: m.maps,
            shape: Shape::Mesh(m.mesh),
            shader,
        });
    }

    let chosen = cameras::choose(path, &opts.camera, &doc.cameras)?;
    let (width, height) = image_size(opts, chosen.and_then(|c| c.camera.aspect_ratio));
    let camera = match chosen {
        Some(placed) => {
            if placed.animated {
                notes.push(format!(
                    "{}: {} hangs under an animated node: using its static pose",
                    path.display(),
                    placed.label()
                ));
            }
            let c = placed.camera;
            Camera {
                position: c.position,
                orientation: c.orientation,
                projection: c.projection,
                width,
                height,
            }
        }
        None => {
            notes.push(match doc.cameras.is_empty() {
                true => format!("no camera in {}: using a framing camera", path.display()),
                false => format!(
                    "{}: --camera framing: using a framing camera",
                    path.display()
                ),
            });
            framing::camera(path, &objects, width, height)?
        }
    };
    let mut lights = doc.lights;
    // Lit by the default environment (pbr) or the default lights (phong).
    let lit_by_default = lights.is_empty() && pbr;
    if lit_by_default {
        notes.push(format!(
            "no lights in {}: lit by the default environment over a grey background, \
             tone-mapped with pbr-neutral (docs/materials.md, \"Default lighting\")",
            path.display()
        ));
    } else if lights.is_empty() {
        notes.push(format!(
            "no lights in {}: using default lights placed relative to the camera \
             (a key light over its shoulder and a weaker fill light from it)",
            path.display()
        ));
        lights.extend(default_lights(&camera));
    }
    let mut scene = Scene {
        textures: doc.textures,
        camera,
        background: Vec3::ZERO,
        shaders,
        objects,
        lights,
    };
    if lit_by_default {
        super::lighting::light_by_default(&mut scene);
    }
    // Named by the file's fields here; `load_scene` validates again, finding nothing.
    if let Err(e) = scene.validate() {
        let shader_of: Vec<usize> = scene.objects.iter().map(|o| o.shader).collect();
        let (field, message) = fields::file_field(&e.field, &e.message, &origins, &shader_of);
        return Err(SceneError::new(path, field, message));
    }
    let mut loaded = Loaded {
        scene,
        notes,
        files: doc.files,
        lit_by_default,
    };
    super::lighting::apply(&mut loaded, &opts.lighting);
    Ok(loaded)
}

/// `--width`/`--height` where given; otherwise derived from the other side and
/// the file's aspect ratio (4:3 without one), or 1024 pixels wide.
fn image_size(opts: &LoadOptions, aspect: Option<f64>) -> (u32, u32) {
    let aspect = aspect.unwrap_or(4.0 / 3.0);
    // `as` saturates, so absurd sizes reach the scene's validation instead of wrapping.
    let side = |x: f64| (x.round() as u32).max(1);
    let (w, h) = match (opts.width, opts.height) {
        (Some(w), None) => (w, side(f64::from(w) / aspect)),
        (None, Some(h)) => (side(f64::from(h) * aspect), h),
        _ => (1024, side(1024.0 / aspect)),
    };
    super::override_size(opts, w, h)
}

/// The key and fill lights of [`default_lights`], in camera space (x right,
/// y up, z back; the camera looks along −z): the directions they travel in
/// and their intensities.
///
/// The key comes from above, behind and to the right of the camera (over
/// its shoulder), about 33° above and 20° to the side of the view; the fill
/// from just left of and below the camera, 13° off the view, so that it
/// reaches what the key leaves in shadow: of the surfaces the camera sees,
/// only those within 13° of grazing can face away from both.
pub const DEFAULT_LIGHTS: [(DVec3, f32); 2] = [
    (DVec3::new(-0.36, -0.7, -1.0), 0.8),
    (DVec3::new(0.2, 0.1, -1.0), 0.35),
];

/// White directional lights fixed to the camera ([`DEFAULT_LIGHTS`]), as
/// model viewers light what they show: wherever the file's camera or the
/// framing camera looks from, what it sees is lit.
/// `--gltf-materials phong` only: glTF's own materials are lit by the
/// default environment ([`super::lighting::light_by_default`]).
fn default_lights(camera: &Camera) -> [Light; 2] {
    let o = camera.orientation;
    DEFAULT_LIGHTS.map(|(d, intensity)| Light {
        kind: LightKind::Directional {
            direction: (o * d).normalize(),
        },
        intensity,
        ambient: Vec3::ZERO,
        diffuse: Vec3::ONE,
        specular: Vec3::ONE,
    })
}

/// [`read`], also returning the index of the scene used (`None`: the file has no scene).
fn read_scene(path: &Path, guard: &Guard) -> Result<(GltfDocument, Option<usize>)> {
    let data = guard
        .read(path, "glTF file")
        .map_err(|e| SceneError::new(path, "", e.0))?;
    let (json, blob) = if data.starts_with(b"glTF") {
        split_glb(path, &data)?
    } else {
        (&data[..], None)
    };
    let document = parse_json(path, json)?;
    let doc = empty_document(path);
    let mut r = Reader {
        file: path,
        guard,
        document: &document,
        json,
        // For what the `gltf` crate does not expose (extensions' objects).
        raw: Some(serde_json::from_slice(json).unwrap_or(serde_json::Value::Null)),
        buffers: Vec::new(),
        decoded: HashMap::new(),
        draco: HashMap::new(),
        doc,
        flags: Flags::default(),
        at: String::new(),
        materials: Vec::new(),
        texture_ids: HashMap::new(),
        pending: Vec::new(),
    };
    // The `gltf` crate's accessors unwrap what its validation should have
    // checked; should one still panic, it becomes an error naming the file
    // and the field being read rather than a crash.
    let walked = crate::panics::catch(|| {
        let (mut doc, scene) = walk(&mut r, &document, blob)?;
        let pending = std::mem::take(&mut r.pending);
        decode::images(&r, pending, &mut doc.textures)?;
        Ok((doc, scene))
    });
    match walked {
        Ok(result) => result,
        Err(panic) => Err(SceneError::new(
            path,
            std::mem::take(&mut r.at),
            format!("internal error in the glTF reader ({panic}); please report this file"),
        )),
    }
}

/// Reads the buffers and walks the default scene of a parsed document.
fn walk(
    r: &mut Reader,
    document: &gltf::Document,
    blob: Option<Vec<u8>>,
) -> Result<(GltfDocument, Option<usize>)> {
    let path = r.file;
    r.load_buffers(document, blob)?;
    let Some(scene) = document
        .default_scene()
        .or_else(|| document.scenes().next())
    else {
        return Ok((std::mem::replace(&mut r.doc, empty_document(path)), None));
    };
    r.flags.animated = document.animations().len() > 0;
    r.flags.quantized = document
        .extensions_used()
        .any(|e| e == "KHR_mesh_quantization");

    let order = scene_nodes(&scene, document.nodes().len()).map_err(|node| {
        // glTF requires disjoint trees; this also stops cycles.
        let message = format!("is reached twice from scene {}", scene.index());
        r.err(format!("nodes[{node}]"), message)
    })?;
    // Every instanced primitive is admitted to the budget before any is
    // read, once per node and per EXT_mesh_gpu_instancing instance.
    for (node, _) in &order {
        if let Some(mesh) = node.mesh() {
            let instances = r.instance_count(node)?;
            for prim in mesh.primitives() {
                let field = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
                let times = instances.map_or(1, |n| n as u64);
                r.charge(&prim, &field, times)
                    .map_err(|e| match instances {
                        Some(n) => r.err(
                            format!("nodes[{}].extensions.{}", node.index(), instancing::NAME),
                            format!("{n} instances of {field}: {}", e.message),
                        ),
                        None => e,
                    })?;
            }
        }
    }
    // Nodes an animation moves, and so everything under them.
    let targets: std::collections::HashSet<usize> = document
        .animations()
        .flat_map(|a| {
            a.channels()
                .map(|c| c.target().node().index())
                .collect::<Vec<_>>()
        })
        .collect();
    let mut worlds = Vec::with_capacity(order.len());
    let mut moving = Vec::with_capacity(order.len());
    for (node, parent) in &order {
        let parent_world = parent.map_or(DMat4::IDENTITY, |p| worlds[p]);
        let world = parent_world * r.local_transform(node)?;
        let animated = targets.contains(&node.index()) || parent.is_some_and(|p| moving[p]);
        r.node(node, &world, animated)?;
        worlds.push(world);
        moving.push(animated);
    }

    let (file, f, notes) = (path.display(), r.flags, &mut r.doc.notes);
    if f.skipped > 0 {
        notes.push(format!(
            "{file}: skipped {} point/line primitives",
            f.skipped
        ));
    }
    if f.animated {
        let note = "skins and animations are not applied: static pose \
                    (morph targets with the file's static weights)";
        notes.push(format!("{file}: {note}"));
    }
    if f.metallic_roughness {
        notes.push(format!("{file}: {METALLIC_ROUGHNESS_NOTE}"));
    }
    let mut ignored: Vec<&str> = Vec::new();
    for e in document.extensions_used() {
        if !extensions::supported(e) && !ignored.contains(&e) {
            ignored.push(e);
        }
    }
    for e in ignored {
        notes.push(format!(
            "{file}: extension {e} is not supported and is ignored"
        ));
    }
    if f.ranged {
        let note = "light range is ignored: penumbra uses pure inverse-square falloff";
        notes.push(format!("{file}: {note}"));
    }
    let doc = std::mem::replace(&mut r.doc, empty_document(path));
    Ok((doc, Some(scene.index())))
}

/// The shader of a KHR_materials_unlit material: one that reflects
/// nothing, so that the point's colour is its emission, the base colour.
pub const UNLIT: Phong = Phong {
    ambient: glam::Vec3::ZERO,
    diffuse: glam::Vec3::ZERO,
    specular: glam::Vec3::ZERO,
    shininess: 1.0,
    textures: crate::scene::PhongTextures {
        ambient: None,
        diffuse: None,
        specular: None,
    },
};

/// The note on files whose materials are not diffuse, which Phong drops
/// (`--gltf-materials phong`, and meshes of JSON scenes, whose shaders the
/// scene names).
pub(crate) const METALLIC_ROUGHNESS_NOTE: &str =
    "metallic-roughness (metallicFactor, roughnessFactor, \
     metallicRoughnessTexture) is not applied: materials are diffuse Phong";

/// The nodes of `scene` depth first, children in file order, each with the
/// position of its parent in the list; `Err(node)` for a node reached twice.
/// A stack rather than recursion, as a long chain of nodes is legal.
fn scene_nodes<'d>(
    scene: &gltf::Scene<'d>,
    count: usize,
) -> std::result::Result<Vec<(gltf::Node<'d>, Option<usize>)>, usize> {
    let mut visited = vec![false; count];
    let mut order = Vec::new();
    let mut stack: Vec<_> = scene.nodes().map(|n| (n, None)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            return Err(node.index());
        }
        let at = order.len();
        let first = stack.len();
        stack.extend(node.children().map(|c| (c, Some(at))));
        stack[first..].reverse();
        order.push((node, parent));
    }
    Ok(order)
}

/// A document with nothing read yet but the file itself.
fn empty_document(path: &Path) -> GltfDocument {
    GltfDocument {
        meshes: vec![],
        camera: None,
        cameras: vec![],
        lights: vec![],
        notes: vec![],
        files: vec![path.to_path_buf()],
        textures: vec![],
    }
}

/// Splits a binary glTF into its JSON chunk and optional BIN chunk, checking
/// every length (the `gltf` crate underflows on a header length below 12).
fn split_glb<'d>(path: &Path, data: &'d [u8]) -> Result<(&'d [u8], Option<Vec<u8>>)> {
    let err = |msg: String| SceneError::new(path, "", format!("invalid GLB: {msg}"));
    let word = |at: usize| -> Option<usize> {
        let bytes = data.get(at..at.checked_add(4)?)?;
        Some(u32::from_le_bytes(bytes.try_into().ok()?) as usize)
    };
    if word(4) != Some(2) {
        return Err(err(format!("version {:?}, expected 2", word(4))));
    }
    let total = word(8).unwrap_or(0);
    if total < 12 || total > data.len() {
        return Err(err(format!(
            "header says {total} bytes, the file has {}",
            data.len()
        )));
    }
    let data = &data[..total];
    let mut chunks = Vec::new();
    let mut at = 12;
    while at < total {
        let (len, kind) = (word(at), data.get(at + 4..at + 8));
        let body = len.and_then(|len| data.get(at + 8..(at + 8).checked_add(len)?));
        let (Some(len), Some(kind), Some(body)) = (len, kind, body) else {
            return Err(err(format!("chunk {} runs past the end", chunks.len())));
        };
        chunks.push((kind, body));
        at += 8 + len.div_ceil(4) * 4; // chunks are 4-byte aligned
    }
    match chunks.as_slice() {
        [(b"JSON", json), rest @ ..] => {
            let bin = rest.iter().find(|(kind, _)| *kind == b"BIN\0");
            Ok((json, bin.map(|(_, b)| b.to_vec())))
        }
        _ => Err(err("the first chunk is not JSON".into())),
    }
}

/// Deserialises and validates the JSON, reporting the path of the offending field.
fn parse_json(path: &Path, json: &[u8]) -> Result<gltf::Document> {
    let invalid = |field: String, e: &dyn std::fmt::Display| {
        SceneError::new(path, field, format!("invalid glTF JSON: {e}"))
    };
    // Indices above u32 first: the crate would wrap them (module [`indices`]).
    // A file that is not JSON is left to the parse below, which names where.
    if let Ok(value) = serde_json::from_slice::<serde_json::Value>(json) {
        if let Some((field, message)) = indices::first_oversized_index(&value) {
            return Err(SceneError::new(path, field, message));
        }
    }
    let mut de = serde_json::Deserializer::from_slice(json);
    let mut root: gltf::json::Root = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let field = Some(e.path().to_string())
            .filter(|p| p != ".")
            .unwrap_or_default();
        invalid(field, e.inner())
    })?;
    de.end().map_err(|e| invalid(String::new(), &e))?;
    // A required extension penumbra lacks explains whatever else fails.
    if let Some((field, message)) = extensions::check_required(&root) {
        return Err(SceneError::new(path, field, message));
    }
    extensions::hide_geometry(&mut root);
    // gltf-json 1.4.1's validation indexes `accessors` with each POSITION
    // before checking the index, so a dangling one would panic there.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let position = prim.attributes.get(&Checked::Valid(Semantic::Positions));
            if position.is_some_and(|i| i.value() >= root.accessors.len()) {
                let field = format!("meshes[{m}].primitives[{p}].attributes.POSITION");
                return Err(SceneError::new(path, field, "Index out of bounds"));
            }
        }
    }
    check_cameras(path, &root)?;
    // What an extension fills is missing for the crate's validation.
    let filled = filled_by_extensions(json);
    let mut errors = Vec::new();
    root.validate(&root, gltf::json::Path::new, &mut |p, e| {
        let p = p().to_string();
        if !(matches!(e, gltf::json::validation::Error::Missing) && filled.contains(&p)) {
            errors.push((p, e));
        }
    });
    if let Some((field, message)) = errors.first() {
        let more = match errors.len() {
            1 => String::new(),
            n => format!(" (and {} more problems)", n - 1),
        };
        return Err(SceneError::new(
            path,
            gltf_path(field),
            format!("{message}{more}"),
        ));
    }
    Ok(gltf::Document::from_json_without_validation(root))
}

/// The fields, as the crate's validation names them, that an extension
/// fills instead: the `bufferView` of the accessors KHR_draco_mesh_compression
/// primitives fill (their `indices` and the attributes their extension
/// object names), and the `source` of textures with a KHR_texture_basisu
/// image.
fn filled_by_extensions(json: &[u8]) -> Vec<String> {
    let Ok(value) = serde_json::from_slice::<serde_json::Value>(json) else {
        return Vec::new();
    };
    let mut filled = Vec::new();
    let prims = value["meshes"].as_array().into_iter().flatten();
    for prim in prims.flat_map(|m| m["primitives"].as_array().into_iter().flatten()) {
        let Some(ext) = prim["extensions"][draco::NAME]["attributes"].as_object() else {
            continue;
        };
        let semantics = ext.keys().map(|k| &prim["attributes"][k]);
        for accessor in std::iter::once(&prim["indices"]).chain(semantics) {
            filled.extend(
                accessor
                    .as_u64()
                    .map(|i| format!("accessors[{i}].bufferView")),
            );
        }
    }
    let textures = value["textures"].as_array().into_iter().flatten();
    for (i, texture) in textures.enumerate() {
        if texture["extensions"][material::BASISU].is_object() {
            filled.push(format!("textures[{i}].source"));
        }
    }
    filled
}

/// Each camera carries the projection object its `type` names: gltf-json
/// 1.4.1's validation misses a camera that has only the other one, and
/// `Camera::projection` unwraps it.
fn check_cameras(path: &Path, root: &gltf::json::Root) -> Result<()> {
    use gltf::json::camera::Type;
    for (i, c) in root.cameras.iter().enumerate() {
        let (name, present) = match c.type_ {
            Checked::Valid(Type::Perspective) => ("perspective", c.perspective.is_some()),
            Checked::Valid(Type::Orthographic) => ("orthographic", c.orthographic.is_some()),
            // An unknown type is reported by the crate's own validation.
            Checked::Invalid => continue,
        };
        // With neither object the crate's validation reports `cameras[i]` itself.
        let other = c.perspective.is_some() || c.orthographic.is_some();
        if !present && other {
            let message = format!("the camera's type is \"{name}\" but it has no `{name}` object");
            return Err(SceneError::new(
                path,
                format!("cameras[{i}].{name}"),
                message,
            ));
        }
    }
    Ok(())
}

/// The `gltf` crate's field path spelled as in the file and in this module's
/// own messages: `attributes["POSITION"]` as `attributes.POSITION`.
fn gltf_path(path: &str) -> String {
    path.replace("[\"", ".")
        .replace("\"]", "")
        .replace("khrLightsPunctual", "KHR_lights_punctual")
}

/// Things worth one note each, gathered while walking the scene.
#[derive(Clone, Copy, Debug, Default)]
struct Flags {
    skipped: usize,
    animated: bool,
    /// The file uses KHR_mesh_quantization: integer vertex attributes.
    quantized: bool,
    metallic_roughness: bool,
    ranged: bool,
}

/// Walks one document: its buffers, then the nodes of the default scene.
struct Reader<'a> {
    file: &'a Path,
    guard: &'a Guard,
    document: &'a gltf::Document,
    /// The JSON text, for what the `gltf` crate does not expose.
    json: &'a [u8],
    /// `json` parsed, once it is needed.
    raw: Option<serde_json::Value>,
    /// `materials[i]` once read.
    materials: Vec<Option<material::Material>>,
    /// The texture decoded from each (image, sRGB) pair.
    texture_ids: HashMap<(usize, bool), TextureId>,
    /// Images checked and charged but not yet decoded: the texture they
    /// become, and the field that names them.
    pending: Vec<(TextureId, super::texture::Pending, String)>,
    /// The field being read, for an error should a dependency panic.
    at: String,
    /// One per `buffers[i]`, exactly `byteLength` long; empty for a
    /// fallback buffer of EXT_meshopt_compression.
    buffers: Vec<Vec<u8>>,
    /// The decoded bytes of each EXT_meshopt_compression bufferView.
    decoded: HashMap<usize, Vec<u8>>,
    /// The values of each accessor a KHR_draco_mesh_compression stream fills.
    draco: HashMap<usize, Vec<f64>>,
    doc: GltfDocument,
    flags: Flags,
}

impl Reader<'_> {
    fn err(&self, field: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::new(self.file, field, message)
    }

    fn fail<T>(&self, field: impl Into<String>, message: impl Into<String>) -> Result<T> {
        Err(self.err(field, message))
    }

    /// Reads every buffer: the GLB binary chunk, a base64 `data:` URI or a file
    /// relative to the glTF file.
    fn load_buffers(&mut self, document: &gltf::Document, mut blob: Option<Vec<u8>>) -> Result<()> {
        let base = self.file.parent().unwrap_or(Path::new(""));
        for buffer in document.buffers() {
            let f = |k: &str| format!("buffers[{}]{k}", buffer.index());
            if meshopt::is_fallback(&self.raw_json()["buffers"][buffer.index()]) {
                // Data for readers without EXT_meshopt_compression only.
                self.buffers.push(Vec::new());
                continue;
            }
            let mut data = match buffer.source() {
                Source::Bin => match blob.take() {
                    Some(blob) => blob,
                    None => return self.fail(f(""), "refers to a GLB binary chunk the file lacks"),
                },
                Source::Uri(uri) if uri.starts_with("data:") => {
                    let payload = uri
                        .split_once(";base64,")
                        .and_then(|(_, b)| decode_base64(b));
                    payload.ok_or_else(|| self.err(f(".uri"), "is not a base64 data: URI"))?
                }
                Source::Uri(uri) => {
                    let Some(relative) = percent_decode(uri).filter(|_| !uri.contains(':')) else {
                        let message = "is neither a relative path nor a base64 data: URI";
                        return self.fail(f(".uri"), message);
                    };
                    let file = base.join(relative);
                    let data = self
                        .guard
                        .read(&file, "buffer")
                        .map_err(|e| self.err(f(".uri"), e.0))?;
                    self.doc.files.push(file);
                    data
                }
            };
            if data.len() < buffer.length() {
                let message = format!(
                    "is {} but the data has {} bytes",
                    buffer.length(),
                    data.len()
                );
                return self.fail(f(".byteLength"), message);
            }
            data.truncate(buffer.length());
            self.buffers.push(data);
        }
        self.decode_meshopt(document)?;
        self.decode_draco()
    }

    /// Decodes every KHR_draco_mesh_compression primitive into the
    /// accessors it fills, each charged against the memory budget by
    /// their declared sizes first.
    fn decode_draco(&mut self) -> Result<()> {
        let raw = self.raw.take().unwrap_or(serde_json::Value::Null);
        let result = self.decode_draco_in(&raw);
        self.raw = Some(raw);
        result
    }

    fn decode_draco_in(&mut self, raw: &serde_json::Value) -> Result<()> {
        let empty = Vec::new();
        let meshes = raw["meshes"].as_array().unwrap_or(&empty);
        for (m, mesh) in meshes.iter().enumerate() {
            let prims = mesh["primitives"].as_array().unwrap_or(&empty);
            for (p, prim) in prims.iter().enumerate() {
                let at = format!("meshes[{m}].primitives[{p}]");
                let c = draco::parse(prim, &raw["accessors"])
                    .map_err(|(key, message)| self.err(format!("{at}.{key}"), message))?;
                let Some(c) = c else { continue };
                let ext = format!("{at}.extensions.{}.bufferView", draco::NAME);
                let Some(view) = self.document.views().nth(c.view) else {
                    let message = format!("{} is not a bufferView of the file", c.view);
                    return self.fail(ext, message);
                };
                self.guard.charge_bytes(c.decoded_len()).map_err(|e| {
                    let what = format!("with this primitive's {} decoded bytes", c.decoded_len());
                    self.err(&ext, e.0.replace("with this image", &what))
                })?;
                let stream = self.view_bytes(&view)?;
                let values = draco::decode(&c, stream)
                    .map_err(|(key, message)| self.err(format!("{at}.{key}"), message))?;
                self.draco.extend(values);
            }
        }
        Ok(())
    }

    /// The file's JSON as a value.
    fn raw_json(&self) -> &serde_json::Value {
        self.raw.as_ref().unwrap_or(&serde_json::Value::Null)
    }

    /// Decodes every EXT_meshopt_compression bufferView, each charged
    /// against the memory budget by its declared size first.
    fn decode_meshopt(&mut self, document: &gltf::Document) -> Result<()> {
        for view in document.views() {
            let i = view.index();
            let at = format!("bufferViews[{i}].extensions.{}", meshopt::NAME);
            let c = meshopt::parse(&self.raw_json()["bufferViews"][i], view.length())
                .map_err(|(key, message)| self.err(format!("{at}.{key}"), message))?;
            let Some(c) = c else { continue };
            let Some(buffer) = self.buffers.get(c.buffer) else {
                let message = format!("{} is not a buffer of the file", c.buffer);
                return self.fail(format!("{at}.buffer"), message);
            };
            let end = c.offset.checked_add(c.length);
            let Some(source) = end.and_then(|end| buffer.get(c.offset..end)) else {
                let message = format!(
                    "{} bytes from offset {} exceed buffers[{}] ({} bytes)",
                    c.length,
                    c.offset,
                    c.buffer,
                    buffer.len()
                );
                return self.fail(format!("{at}.byteLength"), message);
            };
            self.guard.charge_bytes(c.decoded_len()).map_err(|e| {
                let what = format!("with this view's {} decoded bytes", c.decoded_len());
                self.err(format!("{at}.count"), e.0.replace("with this image", &what))
            })?;
            let bytes = meshopt::decode(&c, source).map_err(|m| self.err(&at, m))?;
            self.decoded.insert(i, bytes);
        }
        Ok(())
    }

    /// The node's local matrix, from `matrix` or translation/rotation/scale.
    fn local_transform(&self, node: &gltf::Node) -> Result<DMat4> {
        let field = format!("nodes[{}]", node.index());
        let m = match node.transform() {
            Transform::Matrix { matrix } => {
                DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from)))
            }
            Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => {
                // glTF requires unit quaternions; normalising keeps slightly-off files rigid.
                let Some(q) = DVec4::from_array(rotation.map(f64::from)).try_normalize() else {
                    return self.fail(format!("{field}.rotation"), "must be a unit quaternion");
                };
                let scale = DVec3::from_array(scale.map(f64::from));
                let translation = DVec3::from_array(translation.map(f64::from));
                DMat4::from_scale_rotation_translation(scale, DQuat::from_vec4(q), translation)
            }
        };
        if !m.is_finite() {
            return self.fail(field, "transform must be finite");
        }
        Ok(m)
    }

    /// Collects the node's meshes, camera and light.
    fn node(&mut self, node: &gltf::Node, world: &DMat4, animated: bool) -> Result<()> {
        self.flags.animated |= node.skin().is_some();
        if let Some(mesh) = node.mesh() {
            let label = match node.name() {
                Some(name) => format!("node '{name}' mesh {}", mesh.index()),
                None => format!("node {} mesh {}", node.index(), mesh.index()),
            };
            self.at = format!("nodes[{}]", node.index());
            let weights = morph::weights(node, &mesh);
            let placed: Vec<(DMat4, String)> = match self.instances(node)? {
                Some(instances) => instances
                    .iter()
                    .enumerate()
                    .map(|(k, m)| (*world * *m, format!("{label} instance {k}")))
                    .collect(),
                None => vec![(*world, label)],
            };
            for (world, label) in &placed {
                for prim in mesh.primitives() {
                    let field = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
                    self.at.clone_from(&field);
                    let name = format!("{label} primitive {}", prim.index());
                    if let Some(m) = self.primitive(&prim, world, &weights, &field, name)? {
                        self.doc.meshes.push(m);
                    }
                }
            }
        }
        self.at = format!("nodes[{}]", node.index());
        if let Some(camera) = node.camera() {
            let placed = self.camera(&camera, world, node.index())?;
            self.doc.camera.get_or_insert(placed);
            self.doc.cameras.push(PlacedCamera {
                index: camera.index(),
                name: camera.name().map(str::to_string),
                camera: placed,
                animated,
            });
        }
        if let Some(light) = node.light() {
            let light = self.light(&light, world, node.index())?;
            self.doc.lights.push(light);
        }
        Ok(())
    }

    /// One primitive as a world-space triangle list; `None` for points and lines.
    fn primitive(
        &mut self,
        prim: &gltf::Primitive,
        world: &DMat4,
        weights: &[f64],
        field: &str,
        name: String,
    ) -> Result<Option<GltfMesh>> {
        let mode = prim.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            self.flags.skipped += 1;
            return Ok(None);
        }
        let positions = self.positions(prim, world, weights, field)?;
        let normals = match prim.get(&Semantic::Normals) {
            Some(acc) => self.normals(prim, &acc, world, weights, positions.len(), field)?,
            None => None,
        };
        let indices = self.indices(prim, positions.len(), field)?;
        if mode == Mode::Triangles && indices.len() % 3 != 0 {
            let used = if prim.indices().is_some() {
                "indices"
            } else {
                "attributes.POSITION"
            };
            let message = format!("has {} vertices, not a multiple of 3", indices.len());
            return self.fail(format!("{field}.{used}"), message);
        }
        let mut triangles = triangle_list(mode, &indices);
        // A mirroring transform turns counter-clockwise into clockwise; swapping
        // two vertices keeps the geometric normal on the side the file meant.
        if DMat3::from_mat4(*world).determinant() < 0.0 {
            triangles.iter_mut().for_each(|t| t.swap(1, 2));
        }
        let material = self.material(&prim.material())?;
        let n = positions.len();
        let uvs = self.uv_sets(prim, n, field)?;
        let colours = match prim.get(&Semantic::Colors(0)) {
            Some(acc) => Some(self.colours(&acc, n, field)?),
            None => None,
        };
        // Tangents only serve normal maps.
        let normal_set = material.maps.normal.map(|(t, _)| t.tex_coord as usize);
        let tangents = match (normal_set, prim.get(&Semantic::Tangents)) {
            (Some(_), Some(acc)) => {
                let field = format!("{field}.attributes.TANGENT");
                let raw = self.attribute(&acc, &field, Dimensions::Vec4, Attribute::Tangent)?;
                self.check_attribute(&acc, &raw, 4, n, &field)?;
                let m = DMat3::from_mat4(*world);
                Some(tangents::from_attribute(&raw, m, normals.as_deref()))
            }
            _ => None,
        };
        let mut mesh = Mesh {
            uvs,
            colours,
            tangents,
            positions,
            normals,
            indices: triangles,
        };
        if let (Some(set), None) = (normal_set, &mesh.tangents) {
            if mesh.uvs.get(set).is_some() {
                tangents::generate(&mut mesh, set);
            } else {
                // No texture coordinates, no tangent direction: zero
                // tangents, which leave the normal as it is (texture.rs).
                mesh.tangents = Some(vec![DVec4::new(0.0, 0.0, 0.0, 1.0); n]);
            }
        }
        Ok(Some(GltfMesh {
            mesh,
            base_color: material.base_color,
            phong: material.phong,
            pbr: material.pbr,
            unlit: material.unlit,
            specular_glossiness: material.specular_glossiness,
            maps: material.maps,
            name,
            primitive: field.to_string(),
            material: prim.material().index(),
        }))
    }

    /// TEXCOORD_0 and TEXCOORD_1 (float, or normalised unsigned byte or
    /// short); a missing set 0 below a present set 1 reads as zeros.
    fn uv_sets(
        &self,
        prim: &gltf::Primitive,
        count: usize,
        field: &str,
    ) -> Result<Vec<Vec<DVec2>>> {
        let mut sets = Vec::new();
        for k in 0..2 {
            let Some(acc) = prim.get(&Semantic::TexCoords(k)) else {
                sets.push(None);
                continue;
            };
            let field = format!("{field}.attributes.TEXCOORD_{k}");
            let raw = self.attribute(&acc, &field, Dimensions::Vec2, Attribute::TexCoord)?;
            self.check_attribute(&acc, &raw, 2, count, &field)?;
            sets.push(Some(raw.chunks_exact(2).map(DVec2::from_slice).collect()));
        }
        while sets.last().is_some_and(Option::is_none) {
            sets.pop();
        }
        Ok(sets
            .into_iter()
            .map(|s| s.unwrap_or_else(|| vec![DVec2::ZERO; count]))
            .collect())
    }

    /// COLOR_0 as linear RGBA: VEC3 (alpha 1) or VEC4, float or normalised
    /// unsigned byte or short.
    fn colours(&self, acc: &Accessor, count: usize, field: &str) -> Result<Vec<Vec4>> {
        let field = format!("{field}.attributes.COLOR_0");
        let dims = match acc.dimensions() {
            d @ (Dimensions::Vec3 | Dimensions::Vec4) => d,
            // Reported by `read_accessor` as the wrong shape.
            _ => Dimensions::Vec4,
        };
        let raw = self.unit_attribute(acc, &field, dims, count)?;
        let n = dims.multiplicity();
        Ok(raw
            .chunks_exact(n)
            .map(|c| {
                let c = c.iter().map(|&x| x as f32).collect::<Vec<_>>();
                Vec4::new(c[0], c[1], c[2], c.get(3).copied().unwrap_or(1.0))
            })
            .collect())
    }

    /// A vertex attribute of type float or normalised unsigned byte or
    /// short, as numbers (integers divided by their maximum), one element per vertex.
    fn unit_attribute(
        &self,
        acc: &Accessor,
        field: &str,
        dims: Dimensions,
        count: usize,
    ) -> Result<Vec<f64>> {
        let types = [DataType::F32, DataType::U8, DataType::U16];
        let mut raw = self.read_accessor(acc, field, dims, &types)?;
        let max = match acc.data_type() {
            DataType::U8 => 255.0,
            DataType::U16 => 65535.0,
            _ => 1.0,
        };
        if max != 1.0 {
            if !acc.normalized() {
                let message = format!(
                    "accessors[{}] is {:?} but not normalized (glTF requires normalized integers here)",
                    acc.index(),
                    acc.data_type()
                );
                return self.fail(field, message);
            }
            raw.iter_mut().for_each(|x| *x /= max);
        }
        self.check_attribute(acc, &raw, dims.multiplicity(), count, field)?;
        Ok(raw)
    }

    /// `raw` has one finite element of `n` numbers per vertex.
    fn check_attribute(
        &self,
        acc: &Accessor,
        raw: &[f64],
        n: usize,
        count: usize,
        field: &str,
    ) -> Result<()> {
        if raw.len() != count * n {
            let message = format!("has {} elements for {count} vertices", raw.len() / n);
            return self.fail(field, message);
        }
        if let Some(i) = raw.iter().position(|x| !x.is_finite()) {
            let message = format!(
                "element {} of accessors[{}] is not finite",
                i / n,
                acc.index()
            );
            return self.fail(field, message);
        }
        Ok(())
    }

    /// Admits a triangle primitive to the scene's memory budget and triangle
    /// limit before any of its data is read; an instanced mesh is charged
    /// once per instance. Points and lines are skipped, so cost nothing.
    fn charge(&self, prim: &gltf::Primitive, field: &str, times: u64) -> Result<()> {
        let mode = prim.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            return Ok(());
        }
        let vertices = prim.get(&Semantic::Positions).map_or(0, |a| a.count()) as u64;
        let normals = prim.get(&Semantic::Normals).is_some();
        let indices = prim.indices().map_or(vertices, |a| a.count() as u64);
        let triangles = match mode {
            Mode::Triangles => indices / 3,
            _ => indices.saturating_sub(2),
        };
        let [vertices, indices, triangles] =
            [vertices, indices, triangles].map(|x| x.saturating_mul(times));
        self.guard
            .charge(vertices, normals, indices, triangles)
            .map_err(|e| self.err(field, e.0))?;
        // Texture coordinates, colours and tangents: each read as f64s and
        // then kept (16, 16 and 32 bytes a vertex); generated tangents may
        // split every corner into a vertex of its own.
        let n = |s: Semantic, elem: u64| {
            prim.get(&s)
                .map_or(0, |a| (a.count() as u64).saturating_mul(elem))
        };
        let normal_map = prim.material().normal_texture().is_some();
        let mut bytes = n(Semantic::TexCoords(0), 32)
            .saturating_add(n(Semantic::TexCoords(1), 32))
            .saturating_add(n(Semantic::Colors(0), 48));
        if normal_map {
            bytes = bytes.saturating_add(match prim.get(&Semantic::Tangents) {
                Some(_) => n(Semantic::Tangents, 64),
                // Per corner: MikkTSpace's tangent, and a possible copy of
                // the vertex (position, normal, two uv sets, colour, tangent).
                None => triangles.saturating_mul(3 * (16 + 128)),
            });
        }
        let bytes = bytes.saturating_mul(times);
        if bytes == 0 {
            return Ok(());
        }
        self.guard.charge_bytes(bytes).map_err(|e| {
            let what = "with this primitive's texture coordinates, colours and tangents";
            self.err(field, e.0.replace("with this image", what))
        })
    }

    /// World-space positions, all finite.
    fn positions(
        &self,
        prim: &gltf::Primitive,
        world: &DMat4,
        weights: &[f64],
        at: &str,
    ) -> Result<Vec<DVec3>> {
        let field = format!("{at}.attributes.POSITION");
        let Some(acc) = prim.get(&Semantic::Positions) else {
            return self.fail(field, "is missing");
        };
        let mut raw = self.attribute(&acc, &field, Dimensions::Vec3, Attribute::Position)?;
        self.morph(prim, weights, &mut raw, false, at)?;
        let mut positions = Vec::with_capacity(raw.len() / 3);
        for (i, p) in raw.chunks_exact(3).enumerate() {
            let p = world.transform_point3(DVec3::from_slice(p));
            if !p.is_finite() {
                let message = format!(
                    "vertex {i} of accessors[{}] is not finite: {p}",
                    acc.index()
                );
                return self.fail(field, message);
            }
            positions.push(p);
        }
        Ok(positions)
    }

    /// The vertex indices, each below `count`; `0..count` for a non-indexed primitive.
    fn indices(&self, prim: &gltf::Primitive, count: usize, field: &str) -> Result<Vec<u32>> {
        let Some(acc) = prim.indices() else {
            let count = u32::try_from(count);
            let message = "has more vertices than 32-bit indices can address";
            return count
                .map(|n| (0..n).collect())
                .map_err(|_| self.err(field, message));
        };
        let field = format!("{field}.indices");
        let types = [DataType::U8, DataType::U16, DataType::U32];
        let ix = self.read_accessor(&acc, &field, Dimensions::Scalar, &types)?;
        if let Some((k, v)) = ix.iter().enumerate().find(|(_, &v)| v >= count as f64) {
            let message = format!(
                "index {v} (entry {k} of accessors[{}]) is out of range for {count} vertices",
                acc.index()
            );
            return self.fail(field, message);
        }
        // Exact: each is an integer below `count`.
        Ok(ix.into_iter().map(|v| v as u32).collect())
    }

    /// World-space unit normals, transformed by the inverse transpose so that
    /// they stay perpendicular to the surface under non-uniform scale.
    fn normals(
        &self,
        prim: &gltf::Primitive,
        acc: &Accessor,
        world: &DMat4,
        weights: &[f64],
        count: usize,
        at: &str,
    ) -> Result<Option<Vec<DVec3>>> {
        let field = format!("{at}.attributes.NORMAL");
        let mut raw = self.attribute(acc, &field, Dimensions::Vec3, Attribute::Normal)?;
        if raw.len() != count * 3 {
            return self.fail(
                field,
                format!("has {} normals for {count} vertices", raw.len() / 3),
            );
        }
        self.morph(prim, weights, &mut raw, true, at)?;
        let linear = DMat3::from_mat4(*world);
        if linear.determinant() == 0.0 {
            // A node scaled to nothing (a common way to hide one) leaves only
            // degenerate triangles, which no ray hits: no normals to shade.
            return Ok(None);
        }
        let m = linear.inverse().transpose();
        let mut normals = Vec::with_capacity(count);
        for (i, n) in raw.chunks_exact(3).enumerate() {
            let n = (m * DVec3::from_slice(n)).normalize_or_zero();
            if n == DVec3::ZERO {
                let message = format!(
                    "normal {i} of accessors[{}] is zero or not finite after the node transform",
                    acc.index()
                );
                return self.fail(field, message);
            }
            normals.push(n);
        }
        Ok(Some(normals))
    }

    /// A vertex attribute's accessor of shape `dims` as numbers, of one of
    /// the component types glTF allows for `attribute` (with
    /// KHR_mesh_quantization's where the file uses it), dequantized.
    fn attribute(
        &self,
        acc: &Accessor,
        field: &str,
        dims: Dimensions,
        attribute: Attribute,
    ) -> Result<Vec<f64>> {
        let allowed = quantization::allowed(attribute, self.flags.quantized);
        let ty = acc.data_type();
        let this = (ty, acc.normalized() && ty != DataType::F32);
        if acc.dimensions() == dims && !allowed.contains(&this) {
            let names: Vec<String> = allowed.iter().map(|&t| quantization::name(t)).collect();
            let mut message = format!(
                "accessors[{}] is {}, expected {}",
                acc.index(),
                quantization::name(this),
                names.join(", ")
            );
            if !self.flags.quantized && quantization::allowed(attribute, true).contains(&this) {
                message +=
                    " (KHR_mesh_quantization allows it, but the file does not use that extension)";
            }
            return self.fail(field, message);
        }
        let types: Vec<DataType> = allowed.iter().map(|t| t.0).collect();
        let mut raw = self.read_accessor(acc, field, dims, &types)?;
        quantization::dequantize(&mut raw, this.0, this.1);
        Ok(raw)
    }

    /// An accessor of the expected shape as `count × components` numbers, with
    /// sparse substitution applied; `field` is where the file uses it.
    fn read_accessor(
        &self,
        acc: &Accessor,
        field: &str,
        dims: Dimensions,
        types: &[DataType],
    ) -> Result<Vec<f64>> {
        let name = format!("accessors[{}]", acc.index());
        let (ty, n, count) = (
            acc.data_type(),
            acc.dimensions().multiplicity(),
            acc.count(),
        );
        if acc.dimensions() != dims || !types.contains(&ty) {
            let message = format!(
                "{name} is {ty:?} {:?}, expected {types:?} {dims:?}",
                acc.dimensions()
            );
            return self.fail(field, message);
        }
        let layout = (n, ty);
        let mut values = match acc.view() {
            Some(view) => self.read_view(&view, acc.offset(), count, layout, &name)?,
            None if self.draco.contains_key(&acc.index()) => self.draco[&acc.index()].clone(),
            // Sparse only, starting from zeros. No buffer bounds the count here.
            None if count <= 1 << 24 => vec![0.0; count * n],
            None => return self.fail(format!("{name}.count"), "is too large without a bufferView"),
        };
        if let Some(sparse) = acc.sparse() {
            let (idx, vals, k) = (sparse.indices(), sparse.values(), sparse.count());
            let itype = match idx.index_type() {
                IndexType::U8 => DataType::U8,
                IndexType::U16 => DataType::U16,
                IndexType::U32 => DataType::U32,
            };
            let ifield = format!("{name}.sparse.indices");
            let at = self.read_view(&idx.view(), idx.offset(), k, (1, itype), &ifield)?;
            let vfield = format!("{name}.sparse.values");
            let subst = self.read_view(&vals.view(), vals.offset(), k, layout, &vfield)?;
            for (&i, value) in at.iter().zip(subst.chunks_exact(n)) {
                let i = i as usize;
                let Some(slot) = values.get_mut(i * n..(i + 1) * n) else {
                    return self.fail(
                        ifield,
                        format!("index {i} is out of range for {count} elements"),
                    );
                };
                slot.copy_from_slice(value);
            }
        }
        Ok(values)
    }

    /// `count` elements of `n` components of type `ty` from a buffer view,
    /// after checking that they lie inside it; `field` names the accessor.
    fn read_view(
        &self,
        view: &View,
        offset: usize,
        count: usize,
        (n, ty): (usize, DataType),
        field: &str,
    ) -> Result<Vec<f64>> {
        let bytes = self.view_bytes(view)?;
        let (size, elem) = (ty.size(), ty.size() * n);
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            let message = format!(
                "bufferViews[{}] has byteStride {stride} < {elem}",
                view.index()
            );
            return self.fail(field, message);
        }
        let end = match count {
            0 => Some(0),
            _ => (count - 1)
                .checked_mul(stride)
                .and_then(|x| x.checked_add(offset)?.checked_add(elem)),
        };
        if !matches!(end, Some(end) if end <= bytes.len()) {
            let message = format!(
                "{count} elements of {elem} bytes from offset {offset} (stride {stride}) \
                 do not fit bufferViews[{}] ({} bytes)",
                view.index(),
                bytes.len()
            );
            return self.fail(field, message);
        }
        let mut out = Vec::with_capacity(count * n);
        for i in 0..count {
            for c in 0..n {
                let at = offset + i * stride + c * size;
                out.push(component(&bytes[at..at + size], ty));
            }
        }
        Ok(out)
    }

    /// The bytes of a buffer view (an image's), checked to lie in its buffer.
    fn view_bytes(&self, view: &View) -> Result<&[u8]> {
        if let Some(bytes) = self.decoded.get(&view.index()) {
            return Ok(bytes);
        }
        let b = view.buffer().index();
        if meshopt::is_fallback(&self.raw_json()["buffers"][b]) {
            let message = format!(
                "lies in buffers[{b}], a fallback buffer of {} whose data penumbra does not read, \
                 but the view is not compressed",
                meshopt::NAME
            );
            return self.fail(format!("bufferViews[{}]", view.index()), message);
        }
        let buffer = &self.buffers[b];
        let end = view.offset().checked_add(view.length());
        end.and_then(|end| buffer.get(view.offset()..end))
            .ok_or_else(|| {
                let message = format!(
                    "exceeds buffer {} ({} bytes)",
                    view.buffer().index(),
                    buffer.len()
                );
                self.err(format!("bufferViews[{}]", view.index()), message)
            })
    }

    fn camera(&self, camera: &gltf::Camera, world: &DMat4, node: usize) -> Result<GltfCamera> {
        let f = |k: &str| format!("cameras[{}].{k}", camera.index());
        let (projection, aspect_ratio) = match camera.projection() {
            gltf::camera::Projection::Perspective(p) => {
                let yfov = f64::from(p.yfov());
                if !(yfov > 0.0 && yfov < PI) {
                    return self.fail(
                        f("perspective.yfov"),
                        format!("must be in (0, pi), got {yfov}"),
                    );
                }
                let aspect = p.aspect_ratio().map(f64::from);
                if aspect.is_some_and(|a| !(a > 0.0 && a.is_finite())) {
                    return self.fail(f("perspective.aspectRatio"), "must be positive");
                }
                (
                    Projection::Perspective {
                        vfov_deg: yfov.to_degrees(),
                    },
                    aspect,
                )
            }
            gltf::camera::Projection::Orthographic(o) => {
                let ymag = f64::from(o.ymag());
                if !(ymag > 0.0 && ymag.is_finite()) {
                    return self.fail(
                        f("orthographic.ymag"),
                        format!("must be positive, got {ymag}"),
                    );
                }
                (Projection::Orthographic { half_height: ymag }, None)
            }
        };
        let Some(orientation) = rotation_of(world) else {
            return self.fail(
                format!("nodes[{node}]"),
                "the camera's transform is singular",
            );
        };
        let position = world.w_axis.truncate();
        Ok(GltfCamera {
            position,
            orientation,
            projection,
            aspect_ratio,
        })
    }

    fn light(
        &mut self,
        light: &gltf::khr_lights_punctual::Light,
        world: &DMat4,
        node: usize,
    ) -> Result<Light> {
        let f = |k: &str| {
            format!(
                "extensions.KHR_lights_punctual.lights[{}].{k}",
                light.index()
            )
        };
        let colour = Vec3::from_array(light.color());
        if !colour.is_finite() || colour.min_element() < 0.0 {
            return self.fail(
                f("color"),
                format!("must be finite and non-negative, got {colour}"),
            );
        }
        let intensity = light.intensity();
        if !(intensity >= 0.0 && intensity.is_finite()) {
            return self.fail(
                f("intensity"),
                format!("must be finite and >= 0, got {intensity}"),
            );
        }
        self.flags.ranged |= light.range().is_some();
        let position = world.w_axis.truncate();
        // Directional and spot lights shine along the node's −Z.
        let direction = || {
            let d = (-world.z_axis.truncate()).try_normalize();
            d.ok_or_else(|| {
                self.err(
                    format!("nodes[{node}]"),
                    "the light's transform collapses −Z",
                )
            })
        };
        let kind = match light.kind() {
            Kind::Directional => LightKind::Directional {
                direction: direction()?,
            },
            Kind::Point => LightKind::Point { position },
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => {
                let inner = f64::from(inner_cone_angle);
                // π/2 written in the file rounds up when read as f32; accept it.
                let outer = match f64::from(outer_cone_angle) {
                    o if o > FRAC_PI_2 && o <= FRAC_PI_2 + 1e-6 => FRAC_PI_2,
                    o => o,
                };
                if !(outer > 0.0 && outer <= FRAC_PI_2) {
                    let message = format!("must be in (0, pi/2], got {outer}");
                    return self.fail(f("spot.outerConeAngle"), message);
                }
                if !(inner >= 0.0 && inner < outer) {
                    let message =
                        format!("must be >= 0 and below outerConeAngle {outer}, got {inner}");
                    return self.fail(f("spot.innerConeAngle"), message);
                }
                LightKind::Spot {
                    position,
                    direction: direction()?,
                    inner_angle: inner,
                    outer_angle: outer,
                }
            }
        };
        Ok(Light {
            kind,
            intensity,
            ambient: Vec3::ZERO,
            diffuse: colour,
            specular: colour,
        })
    }
}

/// The rotation of a camera node: keeps its view axis, makes up perpendicular
/// to it and drops scale and shear; `None` if the transform collapses an axis.
fn rotation_of(m: &DMat4) -> Option<DMat3> {
    let back = m.z_axis.truncate().try_normalize()?;
    let y = m.y_axis.truncate();
    let up = (y - back * back.dot(y)).try_normalize()?;
    Some(DMat3::from_cols(up.cross(back), up, back))
}

/// Triangles in the glTF specification's vertex order: strips alternate the
/// order so that every triangle faces the same way; fans pivot on vertex 0.
fn triangle_list(mode: Mode, ix: &[u32]) -> Vec<[u32; 3]> {
    let n = ix.len().saturating_sub(2);
    match mode {
        Mode::TriangleStrip => (0..n)
            .map(|i| [ix[i], ix[i + 1 + i % 2], ix[i + 2 - i % 2]])
            .collect(),
        Mode::TriangleFan => (0..n).map(|i| [ix[i + 1], ix[i + 2], ix[0]]).collect(),
        _ => ix.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    }
}

/// One little-endian component; `b` holds exactly `ty.size()` bytes.
fn component(b: &[u8], ty: DataType) -> f64 {
    match ty {
        DataType::I8 => f64::from(b[0] as i8),
        DataType::U8 => f64::from(b[0]),
        DataType::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
        DataType::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
        DataType::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        DataType::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
    }
}

/// Standard or URL-safe base64, padding optional; `None` on any other character.
fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(text.len() / 4 * 3);
    let (mut acc, mut bits) = (0u32, 0u32);
    for c in text.trim_end_matches('=').bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        };
        acc = (acc << 6 | u32::from(v)) & 0xFFFF;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    Some(out)
}

/// Decodes the `%XX` escapes of a relative URI; `None` if malformed or not UTF-8.
fn percent_decode(uri: &str) -> Option<String> {
    let mut out = Vec::with_capacity(uri.len());
    let mut bytes = uri.bytes();
    while let Some(b) = bytes.next() {
        if b == b'%' {
            let hex = [bytes.next()?, bytes.next()?];
            out.push(u8::from_str_radix(std::str::from_utf8(&hex).ok()?, 16).ok()?);
        } else {
            out.push(b);
        }
    }
    String::from_utf8(out).ok()
}
