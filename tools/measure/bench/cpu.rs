//! A plain multi-threaded Rust CPU implementation of the kernel's algorithm:
//! the baseline the GPU kernel on lavapipe must not be slower than.
//!
//! It is a straightforward port of `shaders/*.wgsl` for the features the
//! bunny scene uses — triangles (with or without vertex normals), infinite
//! planes, directional lights, Phong and Blinn-Phong shaders — on the very
//! same data the GPU gets: the camera-relative `f32` buffers of
//! [`GpuScene::new`] and the BVH of [`GpuScene::build_bvh`] — the same tree
//! (rebuilt by [`GpuScene::build_tree`], which is deterministic). Two
//! choices differ from the kernel's because the kernel's would make this
//! port slower, and the target is to beat the port at its best: it traverses
//! the tree's exact `f32` node boxes, not the kernel's quantised records
//! (decoding them made the port slower), and shadow rays visit the left
//! child first, not the nearer one (the nearer-first order made it slower) —
//! while both made lavapipe faster (docs/bench.md §6; the port's figures are
//! in docs/history.md).
//! Neither changes a result: same hits, same shadow-ray outcomes. The same primary
//! rays through the pixel centres, the same nearest-first BVH traversal with
//! the same widened slab test, the seminar's u,v-first Möller–Trumbore, the
//! same shading sum, and the same shadow rays (skip the starting primitive,
//! Wächter–Binder origin offset for triangles, any-hit traversal). Rows are
//! rendered in parallel with rayon (one thread per core).
//!
//! Spheres, point and spot lights, checkers and area lights are not ported:
//! [`CpuScene::new`] refuses scenes that use them.

use glam::{IVec3, Vec3};
use penumbra::render::layout::{
    node_bounds_f32, GpuScene, Light, Plane, Triangle, VertexNormals, LIGHT_DIRECTIONAL,
    NO_NORMALS, SHADER_CHECKER,
};
use penumbra::scene::{Phong, Shader};
use rayon::prelude::*;

const FAR: f32 = 3.0e38;
const BOX_MISS: f32 = 3.4e38;
const BVH_STACK: usize = 64;
const OFFSET_ORIGIN: f32 = 1.0 / 32.0;
const OFFSET_FLOAT_SCALE: f32 = 1.0 / 65536.0;
const OFFSET_INT_SCALE: f32 = 32.0;

/// The data the CPU renderer reads: a laid-out scene with its BVH.
pub struct CpuScene {
    right: Vec3,
    up: Vec3,
    forward: Vec3,
    orthographic: bool,
    background: Vec3,
    planes: Vec<Plane>,
    triangles: Vec<Triangle>,
    normals: Vec<VertexNormals>,
    lights: Vec<Light>,
    shaders: Vec<(bool, Phong)>,
    nodes: Vec<Node>,
    prims: Vec<u32>,
}

/// A rendered image (RGBA, linear) with its shadow-ray count.
pub struct CpuFrame {
    pub pixels: Vec<[f32; 4]>,
    pub shadow_rays: u64,
}

/// What [`CpuScene::traversal_steps`] found.
pub struct StepModel {
    /// Mean traversal loop iterations per pixel (primary and shadow).
    pub mean: f64,
    /// Useful fraction of SIMD-8 lane-iterations.
    pub utilisation: f64,
}

/// Traversal loop iterations of one pixel.
#[derive(Default)]
struct Steps {
    primary: u32,
    shadow: u32,
}

#[derive(Clone, Copy)]
struct Ray {
    origin: Vec3,
    dir: Vec3,
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    None,
    Plane,
    Triangle,
}

#[derive(Clone, Copy)]
struct Hit {
    found: bool,
    t: f32,
    kind: Kind,
    index: u32,
    u: f32,
    v: f32,
    position: Vec3,
    geometric_normal: Vec3,
    shading_normal: Vec3,
    shader: u32,
}

/// A BVH node with its exact (padded, outward-rounded) `f32` box: an
/// interior node's left child is the next node and `index` its right child;
/// a leaf covers `prims[index..index + count]`.
struct Node {
    min: [f32; 3],
    index: u32,
    max: [f32; 3],
    count: u32,
}

fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

impl CpuScene {
    /// Takes a laid-out scene whose BVH has been built; errors for features
    /// the port does not have.
    pub fn new(g: &GpuScene, shaders: &[Shader]) -> Result<CpuScene, String> {
        if !g.spheres.is_empty() {
            return Err("the CPU port has no spheres".into());
        }
        if g.lights.iter().any(|l| l.kind != LIGHT_DIRECTIONAL) {
            return Err("the CPU port has directional lights only".into());
        }
        if g.shaders.iter().any(|s| s.kind == SHADER_CHECKER) {
            return Err("the CPU port has no checker shader".into());
        }
        // shaders/shading/phong.wgsl and blinn_phong.wgsl: (Blinn?, Phong).
        let shaders = shaders
            .iter()
            .map(|s| match s {
                Shader::Phong(p) => Ok((false, *p)),
                Shader::BlinnPhong(p) => Ok((true, *p)),
                _ => Err("the CPU port has only the Phong and Blinn-Phong shaders".to_string()),
            })
            .collect::<Result<Vec<_>, String>>()?;
        if g.bvh_nodes.is_empty() && !g.triangles.is_empty() {
            return Err("build the BVH first (GpuScene::build_bvh)".into());
        }
        let bvh = g.build_tree();
        let nodes = bvh
            .nodes
            .iter()
            .map(|n| {
                let (min, max) = node_bounds_f32(n.bounds());
                Node {
                    min,
                    index: n.index,
                    max,
                    count: n.count,
                }
            })
            .collect();
        let c = &g.globals.camera;
        Ok(CpuScene {
            right: v3(c.right),
            up: v3(c.up),
            forward: v3(c.forward),
            orthographic: c.orthographic != 0,
            background: v3(g.globals.background),
            planes: g.planes.clone(),
            triangles: g.triangles.clone(),
            normals: g.vertex_normals.clone(),
            lights: g.lights.clone(),
            shaders,
            nodes,
            prims: bvh.prim_refs(g.triangles.len()),
        })
    }

    /// Renders `width`×`height` pixels, rows in parallel.
    pub fn render(&self, width: u32, height: u32) -> CpuFrame {
        let mut pixels = vec![[0f32; 4]; width as usize * height as usize];
        let shadow: u64 = pixels
            .par_chunks_mut(width as usize)
            .enumerate()
            .map(|(y, row)| {
                let mut shadow_rays = 0u64;
                for (x, px) in row.iter_mut().enumerate() {
                    *px = self.pixel(x as u32, y as u32, width, height, &mut shadow_rays);
                }
                shadow_rays
            })
            .sum();
        CpuFrame {
            pixels,
            shadow_rays: shadow,
        }
    }

    fn pixel(&self, x: u32, y: u32, width: u32, height: u32, shadow_rays: &mut u64) -> [f32; 4] {
        self.pixel_steps(x, y, width, height, shadow_rays, &mut Steps::default())
    }

    fn pixel_steps(
        &self,
        x: u32,
        y: u32,
        width: u32,
        height: u32,
        shadow_rays: &mut u64,
        steps: &mut Steps,
    ) -> [f32; 4] {
        let ray = self.primary_ray(x, y, width, height);
        let hit = self.closest_hit(ray, steps);
        if !hit.found {
            return self.background.extend(0.0).to_array();
        }
        self.shade(ray, &hit, shadow_rays, steps)
            .extend(1.0)
            .to_array()
    }

    /// A model of the kernel's SIMD efficiency on lavapipe, which runs an
    /// 8×8 workgroup as SIMD groups of 8 invocations (one row of 8 pixels):
    /// a loop runs until its slowest lane is done. Counts, per pixel, the
    /// iterations of the primary and of the shadow traversal (node visits
    /// plus triangle tests), and returns the mean count and the fraction of
    /// lane-iterations doing useful work: Σ lanes / Σ groups 8·(max primary +
    /// max shadow).
    pub fn traversal_steps(&self, width: u32, height: u32) -> StepModel {
        let rows: Vec<(u64, u64)> = (0..height)
            .into_par_iter()
            .map(|y| {
                let (mut useful, mut issued) = (0u64, 0u64);
                for x0 in (0..width).step_by(8) {
                    let (mut max_p, mut max_s) = (0u32, 0u32);
                    for x in x0..(x0 + 8).min(width) {
                        let mut steps = Steps::default();
                        self.pixel_steps(x, y, width, height, &mut 0, &mut steps);
                        useful += (steps.primary + steps.shadow) as u64;
                        max_p = max_p.max(steps.primary);
                        max_s = max_s.max(steps.shadow);
                    }
                    issued += 8 * (max_p + max_s) as u64;
                }
                (useful, issued)
            })
            .collect();
        let useful: u64 = rows.iter().map(|r| r.0).sum();
        let issued: u64 = rows.iter().map(|r| r.1).sum();
        StepModel {
            mean: useful as f64 / (width as f64 * height as f64),
            utilisation: useful as f64 / issued.max(1) as f64,
        }
    }

    // shaders/camera.wgsl
    fn primary_ray(&self, x: u32, y: u32, width: u32, height: u32) -> Ray {
        let (w, h) = (width as f32, height as f32);
        let ndc_x = (x as f32 + 0.5) / w * 2.0 - 1.0;
        let ndc_y = 1.0 - (y as f32 + 0.5) / h * 2.0;
        let offset = ndc_x * self.right + ndc_y * self.up;
        if self.orthographic {
            return Ray {
                origin: offset,
                dir: self.forward,
            };
        }
        Ray {
            origin: Vec3::ZERO,
            dir: (self.forward + offset).normalize(),
        }
    }

    // shaders/hit.wgsl
    fn closest_hit(&self, ray: Ray, steps: &mut Steps) -> Hit {
        let mut hit = Hit {
            found: false,
            t: FAR,
            kind: Kind::None,
            index: 0,
            u: 0.0,
            v: 0.0,
            position: Vec3::ZERO,
            geometric_normal: Vec3::ZERO,
            shading_normal: Vec3::ZERO,
            shader: 0,
        };
        for (i, p) in self.planes.iter().enumerate() {
            let t = intersect_plane(p, ray);
            if t > 0.0 && t < hit.t {
                hit.found = true;
                hit.t = t;
                hit.kind = Kind::Plane;
                hit.index = i as u32;
            }
        }
        self.bvh_closest(ray, &mut hit, &mut steps.primary);
        if hit.found {
            self.finish_hit(ray, &mut hit);
        }
        hit
    }

    fn finish_hit(&self, ray: Ray, hit: &mut Hit) {
        let p = ray.origin + hit.t * ray.dir;
        let (mut ng, mut ns);
        if hit.kind == Kind::Plane {
            let plane = &self.planes[hit.index as usize];
            ng = v3(plane.normal);
            ns = ng;
            hit.shader = plane.shader;
        } else {
            let tri = &self.triangles[hit.index as usize];
            ng = (v3(tri.v1) - v3(tri.v0))
                .cross(v3(tri.v2) - v3(tri.v0))
                .normalize();
            ns = self.shading_normal(tri, ng, hit.u, hit.v);
            hit.shader = tri.shader;
        }
        if ng.dot(ray.dir) > 0.0 {
            ng = -ng;
        }
        if ns.dot(ray.dir) > 0.0 {
            ns = -ns;
        }
        hit.position = p;
        hit.geometric_normal = ng;
        hit.shading_normal = ns;
    }

    // shaders/primitives/triangle.wgsl
    fn shading_normal(&self, tri: &Triangle, ng: Vec3, u: f32, v: f32) -> Vec3 {
        if tri.normals == NO_NORMALS {
            return ng;
        }
        let n = &self.normals[tri.normals as usize];
        let n0 = Vec3::new(n.n0[0], n.n0[1], n.n0[2]);
        let n1 = Vec3::new(n.n1[0], n.n1[1], n.n1[2]);
        let n2 = Vec3::new(n.n2[0], n.n2[1], n.n2[2]);
        let interpolated = (1.0 - u - v) * n0 + u * n1 + v * n2;
        let len2 = interpolated.dot(interpolated);
        if len2 > 1e-12 {
            interpolated / len2.sqrt()
        } else {
            ng
        }
    }

    // shaders/bvh.wgsl: nearest hit, nearest child first.
    fn bvh_closest(&self, ray: Ray, hit: &mut Hit, steps: &mut u32) {
        if self.nodes.is_empty() {
            return;
        }
        let inv_dir = safe_inverse(ray.dir);
        let mut stack = [0u32; BVH_STACK];
        let mut stack_t = [0f32; BVH_STACK];
        let mut sp = 0usize;
        let mut node_index = 0u32;
        let mut node_t = box_entry(&self.nodes[0], ray.origin, inv_dir, hit.t);
        loop {
            *steps += 1;
            if node_t < hit.t {
                let node = &self.nodes[node_index as usize];
                if node.count == 0 {
                    let left = node_index + 1;
                    let right = node.index;
                    let tl = box_entry(&self.nodes[left as usize], ray.origin, inv_dir, hit.t);
                    let tr = box_entry(&self.nodes[right as usize], ray.origin, inv_dir, hit.t);
                    let left_first = tl <= tr;
                    let (near_t, far_t) = if left_first { (tl, tr) } else { (tr, tl) };
                    if far_t < BOX_MISS {
                        stack[sp] = if left_first { right } else { left };
                        stack_t[sp] = far_t;
                        sp += 1;
                    }
                    node_index = if left_first { left } else { right };
                    node_t = near_t;
                    continue;
                }
                for i in node.index..node.index + node.count {
                    *steps += 1;
                    let prim = self.prims[i as usize];
                    let h = intersect_triangle(&self.triangles[prim as usize], ray, hit.t);
                    if h[0] > 0.0 {
                        hit.found = true;
                        hit.t = h[0];
                        hit.kind = Kind::Triangle;
                        hit.index = prim;
                        hit.u = h[1];
                        hit.v = h[2];
                    }
                }
            }
            if sp == 0 {
                break;
            }
            sp -= 1;
            node_index = stack[sp];
            node_t = stack_t[sp];
        }
    }

    // shaders/bvh.wgsl: any hit before t_max.
    fn bvh_occluded(&self, ray: Ray, t_max: f32, start: &Hit, steps: &mut u32) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let inv_dir = safe_inverse(ray.dir);
        let mut stack = [0u32; BVH_STACK];
        let mut sp = 0usize;
        let mut node_index = 0u32;
        if box_entry(&self.nodes[0], ray.origin, inv_dir, t_max) == BOX_MISS {
            return false;
        }
        loop {
            *steps += 1;
            let node = &self.nodes[node_index as usize];
            if node.count == 0 {
                let left = node_index + 1;
                let right = node.index;
                // Left child first: the kernel takes the nearer one, which
                // made this scalar port 1.2× slower (see the module doc).
                let hit_left =
                    box_entry(&self.nodes[left as usize], ray.origin, inv_dir, t_max) < BOX_MISS;
                let hit_right =
                    box_entry(&self.nodes[right as usize], ray.origin, inv_dir, t_max) < BOX_MISS;
                if hit_left || hit_right {
                    if hit_left && hit_right {
                        stack[sp] = right;
                        sp += 1;
                    }
                    node_index = if hit_left { left } else { right };
                    continue;
                }
            } else {
                for i in node.index..node.index + node.count {
                    *steps += 1;
                    let prim = self.prims[i as usize];
                    if start.kind == Kind::Triangle && start.index == prim {
                        continue;
                    }
                    if intersect_triangle(&self.triangles[prim as usize], ray, t_max)[0] > 0.0 {
                        return true;
                    }
                }
            }
            if sp == 0 {
                break;
            }
            sp -= 1;
            node_index = stack[sp];
        }
        false
    }

    // shaders/shadows.wgsl (robust start, directional lights: t_max = FAR).
    fn occluded(&self, hit: &Hit, to_light: Vec3, distance: f32, steps: &mut Steps) -> bool {
        // (shade() only asks for lights above the geometric surface.)
        let origin = if hit.kind == Kind::Triangle {
            offset_ray_origin(hit.position, hit.geometric_normal)
        } else {
            hit.position
        };
        let ray = Ray {
            origin,
            dir: to_light,
        };
        for (i, p) in self.planes.iter().enumerate() {
            if hit.kind == Kind::Plane && hit.index == i as u32 {
                continue;
            }
            let t = intersect_plane(p, ray);
            if t > 0.0 && t < distance {
                return true;
            }
        }
        self.bvh_occluded(ray, distance, hit, &mut steps.shadow)
    }

    // shaders/shading/shader.wgsl
    fn shade(&self, ray: Ray, hit: &Hit, shadow_rays: &mut u64, steps: &mut Steps) -> Vec3 {
        let (blinn, node) = &self.shaders[hit.shader as usize];
        let n = hit.shading_normal;
        let v = -ray.dir;
        let mut colour = Vec3::ZERO;
        for light in &self.lights {
            colour += node.ambient * v3(light.ambient);
            // Directional: towards the light, unbounded, no falloff.
            let l = -v3(light.direction);
            let (distance, falloff) = (FAR, 1.0f32);
            let ln = l.dot(n);
            // Light below the geometric surface (interpolated normals): the
            // surface itself is in the way, no ray needed.
            if ln <= 0.0 || l.dot(hit.geometric_normal) <= 0.0 {
                continue;
            }
            *shadow_rays += 1;
            if self.occluded(hit, l, distance, steps) {
                continue;
            }
            let lobe = if *blinn {
                blinn_phong_lobe(n, l, v, node.shininess)
            } else {
                phong_lobe(n, l, v, node.shininess)
            };
            colour += falloff
                * light.intensity
                * (node.diffuse * v3(light.diffuse) * ln
                    + node.specular * v3(light.specular) * lobe);
        }
        colour
    }
}

fn intersect_plane(p: &Plane, ray: Ray) -> f32 {
    let n = v3(p.normal);
    let denom = n.dot(ray.dir);
    if denom == 0.0 {
        return -1.0;
    }
    n.dot(v3(p.point) - ray.origin) / denom
}

fn safe_inverse(d: Vec3) -> Vec3 {
    let f = |x: f32| {
        let tiny = 1e-30f32;
        let signed_tiny = if x >= 0.0 { tiny } else { -tiny };
        1.0 / if x.abs() < tiny { signed_tiny } else { x }
    };
    Vec3::new(f(d.x), f(d.y), f(d.z))
}

// The widened slab test of shaders/bvh.wgsl (no operand is NaN there, so
// f32::min/max give the kernel's selects).
fn box_entry(node: &Node, origin: Vec3, inv_dir: Vec3, t_max: f32) -> f32 {
    let t0 = (v3(node.min) - origin) * inv_dir;
    let t1 = (v3(node.max) - origin) * inv_dir;
    let near = t0.min(t1);
    let far = t0.max(t1);
    let t_enter = near.x.max(near.y).max(near.z.max(0.0));
    let t_exit = far.x.min(far.y).min(far.z) * 1.000_000_5;
    if t_enter <= t_exit.min(t_max) {
        t_enter
    } else {
        BOX_MISS
    }
}

/// The seminar's u,v-first Möller–Trumbore: (t, u, v), t = -1 for a miss.
fn intersect_triangle(tri: &Triangle, ray: Ray, t_max: f32) -> [f32; 3] {
    const MISS: [f32; 3] = [-1.0, 0.0, 0.0];
    let (e1, e2) = (v3(tri.v1) - v3(tri.v0), v3(tri.v2) - v3(tri.v0));
    let p = ray.dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return MISS;
    }
    let inv = 1.0 / det;
    let s = ray.origin - v3(tri.v0);
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return MISS;
    }
    let q = s.cross(e1);
    let v = ray.dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return MISS;
    }
    let t = e2.dot(q) * inv;
    if t > 0.0 && t < t_max {
        [t, u, v]
    } else {
        MISS
    }
}

// Wächter and Binder's offset, as in shaders/shadows.wgsl.
fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    // WGSL's f32 → i32 conversion truncates towards zero, like `as`.
    let of_i = IVec3::new(
        (OFFSET_INT_SCALE * n.x) as i32,
        (OFFSET_INT_SCALE * n.y) as i32,
        (OFFSET_INT_SCALE * n.z) as i32,
    );
    let component = |p: f32, o: i32, n: f32| {
        if p.abs() < OFFSET_ORIGIN {
            p + OFFSET_FLOAT_SCALE * n
        } else {
            let o = if p < 0.0 { -o } else { o };
            f32::from_bits((p.to_bits() as i32).wrapping_add(o) as u32)
        }
    };
    Vec3::new(
        component(p.x, of_i.x, n.x),
        component(p.y, of_i.y, n.y),
        component(p.z, of_i.z, n.z),
    )
}

fn spec_pow(x: f32, n: f32) -> f32 {
    if n == 0.0 {
        return 1.0;
    }
    if x <= 0.0 {
        return 0.0;
    }
    x.powf(n)
}

fn phong_lobe(n: Vec3, l: Vec3, v: Vec3, shininess: f32) -> f32 {
    let r = 2.0 * l.dot(n) * n - l;
    spec_pow(r.dot(v).max(0.0), shininess)
}

fn blinn_phong_lobe(n: Vec3, l: Vec3, v: Vec3, shininess: f32) -> f32 {
    let sum = l + v;
    let len2 = sum.dot(sum);
    if len2 == 0.0 {
        return spec_pow(0.0, shininess);
    }
    spec_pow((sum / len2.sqrt()).dot(n).max(0.0), shininess)
}
