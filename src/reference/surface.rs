//! What a surface point carries besides its position and normals, as the
//! contract in [`crate::scene::texture`] defines it: texture coordinates
//! (a triangle's interpolated uv sets, a plane's planar and a sphere's
//! latitude-longitude coordinates), the uv area per world area that the
//! level of detail needs, the vertex colour and tangent; and the alpha
//! tests (`Mask`, `Blend`) that traversal runs on every candidate triangle.

use glam::{DVec2, DVec3, DVec4, Vec4};

use super::hit::Kind;
use super::sampling::{hash3, unit_float};
use super::texture;
use super::World;
use crate::scene::{AlphaMode, Mesh, SurfaceMaps, TextureRef};

/// The vertex attributes of a mesh, for its triangles' surface points.
#[derive(Clone, Debug, Default)]
pub struct MeshAttributes {
    /// Vertex indices, three per triangle (the mesh's).
    pub indices: Vec<[u32; 3]>,
    /// Uv sets, one entry per vertex each.
    pub uvs: Vec<Vec<DVec2>>,
    /// Linear RGBA vertex colours.
    pub colours: Option<Vec<Vec4>>,
    /// Tangents with the bitangent sign in `w`.
    pub tangents: Option<Vec<DVec4>>,
}

impl MeshAttributes {
    /// The attributes of `m` (its indices, uvs, colours and tangents).
    pub fn new(m: &Mesh) -> MeshAttributes {
        MeshAttributes {
            indices: m.indices.clone(),
            uvs: m.uvs.clone(),
            colours: m.colours.clone(),
            tangents: m.tangents.clone(),
        }
    }
}

/// One object of the scene as surface points need it.
#[derive(Clone, Debug)]
pub struct ObjectInfo {
    /// Its normal map, emission and alpha.
    pub maps: SurfaceMaps,
    /// Index of its first triangle among the World's triangles (meshes).
    pub first_triangle: u32,
    /// A mesh's vertex attributes (only kept where the scene is textured or
    /// coloured: [`World`]'s `textured`).
    pub mesh: Option<MeshAttributes>,
}

/// The texture coordinates, colour and tangent at a surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// Uv sets 0 and 1 ((0, 0) where the primitive has no such set).
    pub uv: [DVec2; 2],
    /// Uv area per world area of each set (0 without the set).
    pub uv_per_world: [f64; 2],
    /// Linear RGBA vertex colour ((1, 1, 1, 1) without colours).
    pub colour: DVec4,
    /// Tangent with the bitangent sign in `w`, where the mesh has them.
    pub tangent: Option<DVec4>,
    /// The use-independent level of detail of each uv set
    /// ([`texture::lod_base`]) for a primary hit; `−∞` (level 0,
    /// magnified) for points that traversal tests.
    pub lod_base: [f64; 2],
}

impl Surface {
    /// λ of texture use `t` at this point.
    pub fn lod(&self, world: &World, t: &TextureRef) -> f64 {
        texture::lod(
            self.lod_base[t.tex_coord as usize & 1],
            &world.textures[t.texture],
            t,
        )
    }

    /// Texture use `t` at this point and its λ, linear RGBA.
    pub fn sample(&self, world: &World, t: &TextureRef) -> DVec4 {
        texture::sample(
            &world.textures[t.texture],
            t,
            self.uv[t.tex_coord as usize & 1],
            self.lod(world, t),
        )
    }
}

/// The object primitive `index` of `kind` belongs to.
pub fn object_of(world: &World, kind: Kind, index: u32) -> u32 {
    let i = index as usize;
    match kind {
        Kind::Plane => world.plane_objects[i],
        Kind::Sphere => world.sphere_objects[i],
        Kind::Triangle => world.triangle_objects[i],
    }
}

/// The surface at point `p` of primitive `index` of `kind`, with barycentrics
/// `u`, `v` for a triangle; its `lod_base` is `−∞` (the caller sets it for
/// primary hits).
pub fn at(world: &World, kind: Kind, index: u32, u: f64, v: f64, p: DVec3) -> Surface {
    let mut s = Surface {
        uv: [DVec2::ZERO; 2],
        uv_per_world: [0.0; 2],
        colour: DVec4::ONE,
        tangent: None,
        lod_base: [f64::NEG_INFINITY; 2],
    };
    match kind {
        Kind::Plane => {
            s.uv[0] = texture::plane_uv(world.planes[index as usize].normal, p);
            s.uv_per_world[0] = 1.0;
        }
        Kind::Sphere => {
            let sp = &world.spheres[index as usize];
            (s.uv[0], s.uv_per_world[0]) = texture::sphere_uv(sp.center, sp.radius, p);
        }
        Kind::Triangle => {
            let info = &world.objects[world.triangle_objects[index as usize] as usize];
            let Some(m) = &info.mesh else { return s };
            let idx = m.indices[(index - info.first_triangle) as usize].map(|k| k as usize);
            let w = [1.0 - u - v, u, v];
            let tri = &world.triangles[index as usize];
            let world_area = (tri.v[1] - tri.v[0]).cross(tri.v[2] - tri.v[0]).length();
            for (set, uvs) in m.uvs.iter().take(2).enumerate() {
                let [a, b, c] = idx.map(|k| uvs[k]);
                s.uv[set] = w[0] * a + w[1] * b + w[2] * c;
                s.uv_per_world[set] = (b - a).perp_dot(c - a).abs() / world_area;
            }
            if let Some(cs) = &m.colours {
                let [a, b, c] = idx.map(|k| cs[k].as_dvec4());
                s.colour = w[0] * a + w[1] * b + w[2] * c;
            }
            if let Some(ts) = &m.tangents {
                let [a, b, c] = idx.map(|k| ts[k]);
                s.tangent = Some(w[0] * a + w[1] * b + w[2] * c);
            }
        }
    }
    s
}

/// Which ray an alpha test is for: the pixel and the hash stream of its
/// `Blend` decisions.
#[derive(Clone, Copy, Debug)]
pub struct AlphaRay {
    /// `y·width + x`.
    pub pixel: u32,
    /// `0x0b1e_0000 + pass` for camera rays, `0x0b1f_0000 + pass` for
    /// shadow rays.
    pub stream: u32,
}

impl AlphaRay {
    /// A camera ray of `pixel` in `pass`.
    pub fn camera(pixel: u32, pass: u32) -> AlphaRay {
        AlphaRay {
            pixel,
            stream: 0x0b1e_0000u32.wrapping_add(pass),
        }
    }

    /// A shadow ray of `pixel` in `pass`.
    pub fn shadow(pixel: u32, pass: u32) -> AlphaRay {
        AlphaRay {
            pixel,
            stream: 0x0b1f_0000u32.wrapping_add(pass),
        }
    }
}

/// The alpha `opacity × opacity_texture.a × colour.a` of surface `s` of an
/// object with maps `maps`, the texture sampled at λ = 0.
pub fn alpha(world: &World, maps: &SurfaceMaps, s: &Surface) -> f64 {
    let tex = maps.opacity_texture.map_or(1.0, |t| {
        texture::sample(
            &world.textures[t.texture],
            &t,
            s.uv[t.tex_coord as usize & 1],
            0.0,
        )
        .w
    });
    f64::from(maps.opacity) * tex * s.colour.w
}

/// `Blend`'s threshold ξ for triangle `primitive` (in the GPU's order) on
/// `ray`: `unit_float(hash3(pixel, primitive, seed ^ stream))`.
pub fn blend_threshold(seed: u32, ray: AlphaRay, primitive: u32) -> f64 {
    unit_float(hash3(ray.pixel, primitive, seed ^ ray.stream))
}

/// Whether the point `p` (barycentrics `u`, `v`) of triangle `index` (in
/// the GPU's order) is there for `ray`: always for `Opaque`, where alpha ≥
/// cutoff for `Mask`, where alpha > ξ for `Blend`. (Only triangles have an
/// alpha test: validation keeps planes and spheres opaque.)
pub fn is_there(world: &World, ray: AlphaRay, index: u32, u: f64, v: f64, p: DVec3) -> bool {
    let maps = &world.objects[world.triangle_objects[index as usize] as usize].maps;
    let alpha = || alpha(world, maps, &at(world, Kind::Triangle, index, u, v, p));
    match maps.alpha_mode {
        AlphaMode::Opaque => true,
        AlphaMode::Mask { cutoff } => alpha() >= f64::from(cutoff),
        AlphaMode::Blend => alpha() > blend_threshold(world.seed, ray, index),
    }
}

#[cfg(test)]
mod tests {
    use glam::{DMat3, Vec3};

    use super::*;
    use crate::frame::Sampler as Samples;
    use crate::reference::hit;
    use crate::reference::intersect::Ray;
    use crate::reference::sampling::pcg;
    use crate::reference::shading::shade;
    use crate::scene::{
        Camera, Filter, Light, LightKind, Object, Phong, PhongTextures, Plane, Projection, Sampler,
        Scene, Shader, Shape, Texture, Triangle,
    };

    fn texture(width: u32, height: u32, texels: Vec<[u8; 4]>, srgb: bool) -> Texture {
        Texture {
            label: "t".into(),
            file: None,
            width,
            height,
            texels,
            srgb,
        }
    }

    fn phong(diffuse: f32) -> Shader {
        Shader::Phong(Phong {
            ambient: Vec3::ZERO,
            diffuse: Vec3::splat(diffuse),
            specular: Vec3::ZERO,
            shininess: 1.0,
            textures: PhongTextures::default(),
        })
    }

    /// The square [−1, 1]² at z = 0 facing +Z, uv (0, 0) at its top left
    /// and (1, 1) at its bottom right (A_uv / A_world = 1/4), as triangles
    /// (0, 1, 2) below the diagonal y = x and (0, 2, 3) above it.
    fn square() -> Mesh {
        let p = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
        Mesh {
            positions: p.iter().map(|&(x, y)| DVec3::new(x, y, 0.0)).collect(),
            normals: None,
            indices: vec![[0, 1, 2], [0, 2, 3]],
            uvs: vec![p
                .iter()
                .map(|&(x, y)| DVec2::new((x + 1.0) / 2.0, (1.0 - y) / 2.0))
                .collect()],
            colours: None,
            tangents: None,
        }
    }

    /// A 100×100 camera at (0, 0, 5) looking along −Z, 90° vertically.
    fn scene(objects: Vec<Object>, textures: Vec<Texture>, lights: Vec<Light>) -> Scene {
        let s = Scene {
            camera: Camera {
                position: DVec3::new(0.0, 0.0, 5.0),
                orientation: DMat3::IDENTITY,
                projection: Projection::Perspective { vfov_deg: 90.0 },
                width: 100,
                height: 100,
            },
            background: Vec3::ZERO,
            shaders: vec![phong(1.0)],
            objects,
            lights,
            textures,
        };
        s.validate().expect("a valid test scene");
        s
    }

    fn object(shape: Shape, maps: SurfaceMaps) -> Object {
        Object {
            shape,
            shader: 0,
            maps,
        }
    }

    fn world(s: &Scene) -> World {
        World::new(s, Samples::Stratified, 7)
    }

    #[test]
    fn lod_of_a_head_on_square() {
        let mut s = scene(
            vec![object(Shape::Mesh(square()), SurfaceMaps::NONE)],
            vec![texture(64, 64, vec![[0; 4]; 64 * 64], false)],
            vec![],
        );
        let t = TextureRef::new(0);
        if let Shader::Phong(p) = &mut s.shaders[0] {
            p.textures.diffuse = Some(t);
        }
        let w = world(&s);
        let eye = DVec3::new(0.0, 0.0, 5.0);
        let to = DVec3::new(0.3, 0.2, 0.0) - eye;
        let h = w.closest_hit(&Ray::new(eye, to.normalize())).unwrap();
        let surf = h.surface.unwrap();
        assert!((surf.uv[0] - DVec2::new(0.65, 0.4)).length() < 1e-12);
        assert!((surf.uv_per_world[0] - 0.25).abs() < 1e-15);
        // One pixel spans α = 2·tan(45°)/100; the cone is t·α wide at the
        // hit, seen at cos = 5/t: λ = log2(t·α·t/5) + ½·log2(¼) + ½·log2(64²).
        let dist = to.length();
        let alpha = 2.0 * 45f64.to_radians().tan() / 100.0;
        let want = (dist * alpha * dist / 5.0).log2() - 1.0 + 6.0;
        let got = surf.lod(&w, &t);
        assert!((got - want).abs() < 1e-12, "{got} {want}");
        // About log2(64/20): the 2×2 square covers about 20 of the 100
        // pixels that span 10 units at distance 5, for its 64 texels.
        assert!((got - (64.0f64 / 20.0).log2()).abs() < 0.02, "{got}");
    }

    #[test]
    fn normal_map_tilts_the_shading_normal() {
        let mut m = square();
        m.tangents = Some(vec![DVec4::new(1.0, 0.0, 0.0, 1.0); 4]);
        let bytes = [200u8, 128, 230, 255];
        let maps = SurfaceMaps {
            normal: Some((TextureRef::new(0), 1.0)),
            ..SurfaceMaps::NONE
        };
        let s = scene(
            vec![object(Shape::Mesh(m), maps)],
            vec![texture(1, 1, vec![bytes], false)],
            vec![],
        );
        let w = world(&s);
        let h = w
            .closest_hit(&Ray::new(DVec3::new(0.3, 0.2, 5.0), -DVec3::Z))
            .unwrap();
        // t = 2·byte/255 − 1 along (T, B, n) = (X, Y, Z).
        let t = DVec3::new(200.0, 128.0, 230.0) * (2.0 / 255.0) - DVec3::ONE;
        assert!((h.shading_normal - t.normalize()).length() < 1e-12);
        assert_eq!(h.geometric_normal, DVec3::Z);
        let angle = h.shading_normal.dot(DVec3::Z).acos();
        let want = (t.x.hypot(t.y)).atan2(t.z);
        assert!((angle - want).abs() < 1e-12 && angle > 0.3, "{angle}");
        // Seen from behind, the tilted normal turns to face the viewer.
        let back = w
            .closest_hit(&Ray::new(DVec3::new(0.3, 0.2, -5.0), DVec3::Z))
            .unwrap();
        assert!((back.shading_normal + t.normalize()).length() < 1e-12);
    }

    /// A floor (y = 0) under a unit quad at y = 1 whose left half (x < 0)
    /// is cut out by a 2×1 alpha texture, lit straight from above.
    fn cut_out() -> Scene {
        let mut quad = square();
        quad.positions = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .iter()
            .map(|&(x, z)| DVec3::new(x, 1.0, z))
            .collect();
        quad.uvs = vec![quad
            .positions
            .iter()
            .map(|p| DVec2::new((p.x + 1.0) / 2.0, (p.z + 1.0) / 2.0))
            .collect()];
        let mut t = TextureRef::new(0);
        t.sampler = Sampler {
            mag: Filter::Nearest,
            ..Sampler::default()
        };
        let maps = SurfaceMaps {
            alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
            opacity_texture: Some(t),
            ..SurfaceMaps::NONE
        };
        let floor = Shape::Plane(Plane {
            point: DVec3::ZERO,
            normal: DVec3::Y,
        });
        scene(
            vec![
                object(floor, SurfaceMaps::NONE),
                object(Shape::Mesh(quad), maps),
            ],
            vec![texture(2, 1, vec![[9, 9, 9, 0], [9, 9, 9, 255]], true)],
            vec![Light {
                kind: LightKind::Directional {
                    direction: -DVec3::Y,
                },
                intensity: 1.0,
                ambient: Vec3::ZERO,
                diffuse: Vec3::ONE,
                specular: Vec3::ZERO,
            }],
        )
    }

    #[test]
    fn mask_cuts_out_for_camera_and_shadow_rays() {
        let w = world(&cut_out());
        let down = |x: f64| {
            let r = Ray::new(DVec3::new(x, 5.0, 0.0), -DVec3::Y);
            w.closest_hit(&r).unwrap()
        };
        // Through the hole to the floor at t = 5; the solid half at t = 4.
        let (hole, solid) = (down(-0.5), down(0.5));
        assert_eq!((hole.kind, hole.t), (Kind::Plane, 5.0));
        assert_eq!((solid.kind, solid.t), (Kind::Triangle, 4.0));
        // The floor seen under the quad: lit (k_d·I_d·l·n = 1) under the
        // hole, in shadow under the solid half.
        let lit = |x: f64| {
            let r = Ray::new(
                DVec3::new(x, 0.5, 3.0),
                DVec3::new(0.0, -0.5, -3.0).normalize(),
            );
            let h = w.closest_hit(&r).unwrap();
            assert_eq!(h.kind, Kind::Plane);
            let mut rays = 0;
            let c = shade(&w, &r, &h, 0, 0, &mut rays);
            assert_eq!(rays, 1);
            c
        };
        assert!((lit(-0.5) - DVec3::ONE).length() < 1e-12, "{}", lit(-0.5));
        assert_eq!(lit(0.5), DVec3::ZERO);
    }

    #[test]
    fn blend_is_a_deterministic_hash_of_pixel_primitive_and_pass() {
        // A triangle first, so the square's triangles are 1 and 2 in the
        // GPU's order.
        let other = Shape::Triangle(Triangle {
            vertices: [
                DVec3::new(5.0, 5.0, 0.0),
                DVec3::new(6.0, 5.0, 0.0),
                DVec3::new(5.0, 6.0, 0.0),
            ],
        });
        let maps = SurfaceMaps {
            alpha_mode: AlphaMode::Blend,
            opacity: 0.5,
            ..SurfaceMaps::NONE
        };
        let s = scene(
            vec![
                object(other, SurfaceMaps::NONE),
                object(Shape::Mesh(square()), maps),
            ],
            vec![],
            vec![],
        );
        let w = world(&s);
        // Below the diagonal: triangle (0, 1, 2), index 1.
        let ray = Ray::new(DVec3::new(0.3, 0.2, 5.0), -DVec3::Z);
        let seed = 7u32;
        let mut hits = 0;
        for pixel in 0..4096u32 {
            let h = hit::closest_hit(&w, &ray, AlphaRay::camera(pixel, 0));
            // ξ = unit_float(hash3(pixel, 1, seed ^ 0x0b1e_0000)), written out.
            let hash = pcg(pixel ^ pcg(1 ^ pcg(seed ^ 0x0b1e_0000)));
            let xi = f64::from(hash >> 8) / 16_777_216.0;
            assert_eq!(h.is_some(), 0.5 > xi, "pixel {pixel}");
            assert_eq!(
                h.is_some(),
                hit::closest_hit(&w, &ray, AlphaRay::camera(pixel, 0)).is_some()
            );
            if let Some(h) = h {
                assert_eq!((h.index, h.t), (1, 5.0));
                hits += 1;
            }
        }
        // Probability alpha = ½ (4096 draws: σ ≈ 0.008).
        let f = f64::from(hits) / 4096.0;
        assert!((f - 0.5).abs() < 0.05, "{f}");
        // Other passes and shadow rays draw other thresholds.
        let differs = |a: AlphaRay, b: AlphaRay| {
            (0..256)
                .filter(|&p| {
                    let (a, b) = (AlphaRay { pixel: p, ..a }, AlphaRay { pixel: p, ..b });
                    blend_threshold(seed, a, 1) != blend_threshold(seed, b, 1)
                })
                .count()
        };
        assert!(differs(AlphaRay::camera(0, 0), AlphaRay::camera(0, 1)) > 250);
        assert!(differs(AlphaRay::camera(0, 0), AlphaRay::shadow(0, 0)) > 250);
    }

    #[test]
    fn phong_textures_vertex_colours_and_emission() {
        let mut m = square();
        let colour = Vec4::new(0.5, 1.0, 0.25, 1.0);
        m.colours = Some(vec![colour; 4]);
        let srgb = |t: [u8; 4]| texture(1, 1, vec![t], true);
        let (ta, td, te) = (
            [200u8, 100, 50, 255],
            [188, 20, 250, 255],
            [255, 128, 0, 255],
        );
        let maps = SurfaceMaps {
            emission: Vec3::new(0.1, 0.2, 0.3),
            emission_texture: Some(TextureRef::new(2)),
            ..SurfaceMaps::NONE
        };
        let mut s = scene(
            vec![object(Shape::Mesh(m), maps)],
            vec![srgb(ta), srgb(td), srgb(te)],
            vec![Light {
                kind: LightKind::Directional {
                    direction: -DVec3::Z,
                },
                intensity: 2.0,
                ambient: Vec3::new(0.1, 0.2, 0.3),
                diffuse: Vec3::new(1.0, 0.5, 0.25),
                specular: Vec3::ZERO,
            }],
        );
        let (ka, kd) = (Vec3::splat(0.5), Vec3::splat(0.8));
        s.shaders[0] = Shader::Phong(Phong {
            ambient: ka,
            diffuse: kd,
            specular: Vec3::ZERO,
            shininess: 1.0,
            textures: PhongTextures {
                ambient: Some(TextureRef::new(0)),
                diffuse: Some(TextureRef::new(1)),
                specular: None,
            },
        });
        let w = world(&s);
        let r = Ray::new(DVec3::new(0.3, 0.2, 5.0), -DVec3::Z);
        let h = w.closest_hit(&r).unwrap();
        let mut rays = 0;
        let got = shade(&w, &r, &h, 0, 0, &mut rays);
        let dec = |t: [u8; 4]| {
            DVec3::new(
                srgb_to_linear(t[0]),
                srgb_to_linear(t[1]),
                srgb_to_linear(t[2]),
            )
        };
        use crate::scene::texture::srgb_to_linear;
        // emission·tex_e + k_a·tex_a·I_a + k_d·tex_d·colour·I_d·intensity·(l·n = 1).
        let want = Vec3::new(0.1, 0.2, 0.3).as_dvec3() * dec(te)
            + ka.as_dvec3() * dec(ta) * Vec3::new(0.1, 0.2, 0.3).as_dvec3()
            + kd.as_dvec3()
                * dec(td)
                * colour.truncate().as_dvec3()
                * Vec3::new(1.0, 0.5, 0.25).as_dvec3()
                * 2.0;
        assert!((got - want).length() < 1e-12, "{got} {want}");
        // Emission is not a light and needs none: without lights it is all
        // that is left.
        let mut dark = s.clone();
        dark.lights.clear();
        let w = world(&dark);
        let h = w.closest_hit(&r).unwrap();
        let got = shade(&w, &r, &h, 0, 0, &mut rays);
        assert!((got - Vec3::new(0.1, 0.2, 0.3).as_dvec3() * dec(te)).length() < 1e-12);
    }
}
