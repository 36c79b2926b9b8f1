// Bounding volume hierarchy traversal (the host builds it: src/bvh.rs).
// Nodes are depth-first: an interior node's left child is the next node and
// `index` holds its right child; a leaf's `index` and `count` give a range of
// `bvh_prims`, each a triangle index or a sphere index with PRIM_SPHERE set.

// Mirrored by render::layout::BvhNode.
struct BvhNode {
    min: vec3<f32>,
    index: u32,
    max: vec3<f32>,
    count: u32,
}

const PRIM_SPHERE: u32 = 0x80000000u;
// bvh::MAX_DEPTH: the tree is never deeper, so the stack cannot overflow.
const BVH_STACK: u32 = 64u;
const BOX_MISS: f32 = 3.4e38;

@group(0) @binding(9) var<storage, read> bvh_nodes: array<BvhNode>;
@group(0) @binding(10) var<storage, read> bvh_prims: array<u32>;

// 1/d with zero components replaced by a tiny value of the same sign, so the
// slab test never computes 0 * inf = NaN.
fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let tiny = vec3<f32>(1e-30);
    let signed_tiny = select(-tiny, tiny, d >= vec3<f32>(0.0));
    return 1.0 / select(d, signed_tiny, abs(d) < tiny);
}

// Distance at which the ray enters the box, or BOX_MISS. The exit distance is
// widened by 1 + 2γ₃ (γ₃ = 3u/(1 − 3u), u = 2⁻²⁴) so rounding in the slab test
// never loses a hit: Ize, "Robust BVH Ray Traversal" (JCGT 2013).
fn box_entry(node: BvhNode, origin: vec3<f32>, inv_dir: vec3<f32>, t_max: f32) -> f32 {
    let t0 = (node.min - origin) * inv_dir;
    let t1 = (node.max - origin) * inv_dir;
    // Comparisons and selects rather than min/max: no operand can be NaN
    // (inv_dir is finite and non-zero), and lavapipe spends three
    // instructions on a NaN-aware min or max against two here.
    let swap = t1 < t0;
    let near = select(t0, t1, swap);
    let far = select(t1, t0, swap);
    let near_xy = select(near.x, near.y, near.y > near.x);
    let near_z = select(near.z, 0.0, near.z < 0.0);
    let t_enter = select(near_xy, near_z, near_z > near_xy);
    let far_xy = select(far.x, far.y, far.y < far.x);
    // 1.0000005 rounds up to 1 + 4·2⁻²³ in f32, just above 1 + 2γ₃.
    let t_exit = select(far_xy, far.z, far.z < far_xy) * 1.0000005;
    if t_enter <= min(t_exit, t_max) {
        return t_enter;
    }
    return BOX_MISS;
}

// Nearest hit among the BVH's spheres and triangles, nearest child first.
fn bvh_closest(ray: Ray, hit: ptr<function, Hit>) {
    if globals.num_bvh_nodes == 0u {
        return;
    }
    let inv_dir = safe_inverse(ray.dir);
    var stack: array<u32, BVH_STACK>;
    var stack_t: array<f32, BVH_STACK>;
    var sp = 0u;
    var node_index = 0u;
    var node_t = box_entry(bvh_nodes[0], ray.origin, inv_dir, (*hit).t);
    // "While-while" (Aila and Laine 2009): every lane descends to a leaf
    // first, so the lanes of a SIMD group test their leaves together.
    loop {
        var leaf = false;
        loop {
            if node_t >= (*hit).t {
                break;
            }
            let node = bvh_nodes[node_index];
            if node.count != 0u {
                leaf = true;
                break;
            }
            let left = node_index + 1u;
            let right = node.index;
            let tl = box_entry(bvh_nodes[left], ray.origin, inv_dir, (*hit).t);
            let tr = box_entry(bvh_nodes[right], ray.origin, inv_dir, (*hit).t);
            let left_first = tl <= tr;
            let near_t = select(tr, tl, left_first);
            let far_t = select(tl, tr, left_first);
            if far_t < BOX_MISS {
                stack[sp] = select(left, right, left_first);
                stack_t[sp] = far_t;
                sp++;
            }
            node_index = select(right, left, left_first);
            node_t = near_t;
        }
        if leaf {
            let node = bvh_nodes[node_index];
            for (var i = node.index; i < node.index + node.count; i++) {
                let prim = bvh_prims[i];
                if (prim & PRIM_SPHERE) != 0u {
                    closest_sphere(prim & ~PRIM_SPHERE, ray, hit);
                } else {
                    closest_triangle(prim, ray, hit);
                }
            }
        }
        if sp == 0u {
            break;
        }
        sp--;
        node_index = stack[sp];
        node_t = stack_t[sp];
    }
}

// Whether any BVH primitive blocks `ray` before `t_max` (any-hit: stops at the
// first blocker found). Nearer child first here too: blockers close to the
// surface point are found sooner (docs/bench.md §6 has the measurement).
fn bvh_occluded(ray: Ray, t_max: f32, start: Hit) -> bool {
    if globals.num_bvh_nodes == 0u {
        return false;
    }
    let inv_dir = safe_inverse(ray.dir);
    var stack: array<u32, BVH_STACK>;
    var sp = 0u;
    var node_index = 0u;
    if box_entry(bvh_nodes[0], ray.origin, inv_dir, t_max) == BOX_MISS {
        return false;
    }
    loop {
        let node = bvh_nodes[node_index];
        if node.count == 0u {
            let left = node_index + 1u;
            let right = node.index;
            let tl = box_entry(bvh_nodes[left], ray.origin, inv_dir, t_max);
            let tr = box_entry(bvh_nodes[right], ray.origin, inv_dir, t_max);
            let hit_left = tl < BOX_MISS;
            let hit_right = tr < BOX_MISS;
            if hit_left || hit_right {
                let left_first = tl <= tr;
                if hit_left && hit_right {
                    stack[sp] = select(left, right, left_first);
                    sp++;
                }
                node_index = select(right, left, left_first);
                continue;
            }
        } else {
            for (var i = node.index; i < node.index + node.count; i++) {
                let prim = bvh_prims[i];
                if (prim & PRIM_SPHERE) != 0u {
                    if sphere_blocks(prim & ~PRIM_SPHERE, ray, t_max, start) {
                        return true;
                    }
                } else if triangle_blocks(prim, ray, t_max, start) {
                    return true;
                }
            }
        }
        if sp == 0u {
            break;
        }
        sp--;
        node_index = stack[sp];
    }
    return false;
}
