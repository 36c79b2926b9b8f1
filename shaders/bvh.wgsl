// Bounding volume hierarchy traversal (the host builds the tree: src/bvh.rs,
// and encodes it: src/render/quantised_bvh.rs). A record holds an interior
// node's two children: their boxes as 8-bit steps in the node's frame, and
// a reference to each, a record index or BVH_LEAF | the leaf's first entry
// of `bvh_prims`. An entry is a triangle index, or a sphere index with
// PRIM_SPHERE set; the leaf's last entry has PRIM_LAST set. A leaf's entries
// start at a multiple of PRIMS_PER_TEXEL (quantised_bvh::align_leaves), so
// the traversal loads them a texel at a time. Record 0 is the root's (the
// root's own box is never tested: its children's lie inside).

// Mirrored by render::layout::BvhNode; fetched by bvh_record.
struct BvhNode {
    // Frame: per axis its lower corner k * 2^e, the signed k in the upper 24
    // bits and the step's biased exponent e + 127 in the low 8.
    origin: vec3<u32>,
    left: u32,
    // Left child's lower and upper corner, then the right child's, a byte
    // per coordinate.
    quantised: vec3<u32>,
    right: u32,
}

const PRIM_SPHERE: u32 = 0x80000000u;
const PRIM_LAST: u32 = 0x40000000u;
const PRIM_INDEX: u32 = 0x3fffffffu;
const BVH_LEAF: u32 = 0x80000000u;
// The right child of a tree that is a single leaf.
const BVH_NONE: u32 = 0xffffffffu;
// bvh::MAX_DEPTH: the tree is never deeper, so the stack cannot overflow.
const BVH_STACK: u32 = 64u;
// Stack entries kept in registers (a vec4) before any goes to the array.
const STACK_REGISTERS: u32 = 4u;
const BOX_MISS: f32 = 3.4e38;
// 16-byte texels per record (32 bytes).
const BVH_RECORD_TEXELS: u32 = 2u;
// Primitive references per texel of `bvh_prims`.
const PRIMS_PER_TEXEL: u32 = 4u;

// Records are texels (shaders/texels.wgsl says why).
@group(0) @binding(9) var bvh_nodes: texture_storage_2d<rgba32uint, read>;
// The references as texels too: a leaf's first texel holds up to four of
// its entries, where a storage-buffer load per entry cost a loop over the
// lanes each (docs/stages.md measures it).
@group(0) @binding(10) var bvh_prims: texture_storage_2d<rgba32uint, read>;

// The same records and references as storage buffers, for the packet
// traversal (PACKET_TRAVERSAL; placeholders otherwise): it loads them at a
// subgroup-uniform index, which lavapipe does as one scalar load for the
// SIMD group, where a texel load is a load per lane.
@group(0) @binding(29) var<storage, read> bvh_node_words: array<BvhNode>;
@group(0) @binding(30) var<storage, read> bvh_prim_words: array<u32>;

// Entry `c` (0 to 3) of a texel of references.
fn texel_entry(four: vec4<u32>, c: u32) -> u32 {
    return select(select(four.x, four.y, c == 1u), select(four.z, four.w, c == 3u), c >= 2u);
}

// Record `i`, from its texels: the struct's words in order.
fn bvh_record(i: u32) -> BvhNode {
    let base = i * BVH_RECORD_TEXELS;
    let a = textureLoad(bvh_nodes, texel(base));
    let b = textureLoad(bvh_nodes, texel(base + 1u));
    return BvhNode(a.xyz, a.w, b.xyz, b.w);
}

// Entry distances of a record's two children (BOX_MISS where missed). The
// decoding is exact: the encoder put every corner on a grid of f32 values
// (origin + q * 2^e, no rounding), below or above the child's box.
fn child_entries(node: BvhNode, origin: vec3<f32>, inv_dir: vec3<f32>, t_max: f32) -> vec2<f32> {
    let step = bitcast<vec3<f32>>((node.origin & vec3<u32>(255u)) << vec3<u32>(23u));
    // k * 2^e is exact: |k| < 2^23, and 2^e and the product are normal.
    let o = vec3<f32>(bitcast<vec3<i32>>(node.origin) >> vec3<u32>(8u)) * step;
    let q = node.quantised;
    let byte = vec3<u32>(255u);
    let left_lo = vec3<f32>(vec3<u32>(q.x, q.x >> 8u, q.x >> 16u) & byte);
    let left_hi = vec3<f32>(vec3<u32>(q.x >> 24u, q.y, q.y >> 8u) & byte);
    let right_lo = vec3<f32>(vec3<u32>(q.y >> 16u, q.y >> 24u, q.z) & byte);
    let right_hi = vec3<f32>(vec3<u32>(q.z >> 8u, q.z >> 16u, q.z >> 24u) & byte);
    let tl = box_entry(o + left_lo * step, o + left_hi * step, origin, inv_dir, t_max);
    var tr = box_entry(o + right_lo * step, o + right_hi * step, origin, inv_dir, t_max);
    if node.right == BVH_NONE {
        tr = BOX_MISS;
    }
    return vec2<f32>(tl, tr);
}

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
fn box_entry(lo: vec3<f32>, hi: vec3<f32>, origin: vec3<f32>, inv_dir: vec3<f32>, t_max: f32) -> f32 {
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
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
    if PACKET_TRAVERSAL {
        bvh_closest_packet(ray, hit);
        return;
    }
    let inv_dir = safe_inverse(ray.dir);
    var stack: array<u32, BVH_STACK>;
    var stack_t: array<f32, BVH_STACK>;
    var sp = 0u;
    // The stack's newest entries (up to STACK_REGISTERS, newest in .x) live
    // in vector registers and only older ones in the arrays: lavapipe keeps
    // a per-lane array in memory, read and written a lane at a time, so most
    // pushes and pops now never touch it (docs/bench.md §6).
    var top = vec4<u32>();
    var top_t = vec4<f32>();
    var held = 0u;
    var node = 0u;
    var node_t = 0.0;
    // "While-while" (Aila and Laine 2009): every lane descends to a leaf
    // first, so the lanes of a SIMD group test their leaves together.
    loop {
        var leaf = false;
        loop {
            if node_t >= (*hit).t {
                break;
            }
            if (node & BVH_LEAF) != 0u {
                leaf = true;
                break;
            }
            let record = bvh_record(node);
            let t = child_entries(record, ray.origin, inv_dir, (*hit).t);
            let left_first = t.x <= t.y;
            let near_t = select(t.y, t.x, left_first);
            let far_t = select(t.x, t.y, left_first);
            if far_t < BOX_MISS {
                // When the registers are full their oldest entry spills.
                if held == STACK_REGISTERS {
                    stack[sp] = top.w;
                    stack_t[sp] = top_t.w;
                    sp++;
                } else {
                    held++;
                }
                top = vec4<u32>(select(record.left, record.right, left_first), top.xyz);
                top_t = vec4<f32>(far_t, top_t.xyz);
            }
            node = select(record.right, record.left, left_first);
            node_t = near_t;
        }
        if leaf {
            var i = (node & ~BVH_LEAF) / PRIMS_PER_TEXEL;
            var last = false;
            loop {
                let four = textureLoad(bvh_prims, texel(i));
                for (var c = 0u; c < PRIMS_PER_TEXEL; c++) {
                    let prim = texel_entry(four, c);
                    if (prim & PRIM_SPHERE) != 0u {
                        closest_sphere(prim & PRIM_INDEX, ray, hit);
                    } else {
                        closest_triangle(prim & PRIM_INDEX, ray, hit);
                    }
                    if (prim & PRIM_LAST) != 0u {
                        last = true;
                        break;
                    }
                }
                if last {
                    break;
                }
                i++;
            }
        }
        if held > 0u {
            node = top.x;
            node_t = top_t.x;
            top = top.yzwx;
            top_t = top_t.yzwx;
            held--;
        } else if sp > 0u {
            sp--;
            node = stack[sp];
            node_t = stack_t[sp];
        } else {
            break;
        }
    }
}

// Whether any BVH primitive blocks `ray` before `t_max` (any-hit: stops at the
// first blocker found). Nearer child first here too: blockers close to the
// surface point are found sooner (docs/bench.md §6 has the measurement).
fn bvh_occluded(ray: Ray, t_max: f32, start: Hit) -> bool {
    if globals.num_bvh_nodes == 0u {
        return false;
    }
    if PACKET_TRAVERSAL {
        return bvh_occluded_packet(ray, t_max, start);
    }
    let inv_dir = safe_inverse(ray.dir);
    var stack: array<u32, BVH_STACK>;
    var sp = 0u;
    // Newest entries in registers, as in bvh_closest.
    var top = vec4<u32>();
    var held = 0u;
    var node = 0u;
    loop {
        if (node & BVH_LEAF) == 0u {
            let record = bvh_record(node);
            let t = child_entries(record, ray.origin, inv_dir, t_max);
            let hit_left = t.x < BOX_MISS;
            let hit_right = t.y < BOX_MISS;
            if hit_left || hit_right {
                let left_first = t.x <= t.y;
                if hit_left && hit_right {
                    if held == STACK_REGISTERS {
                        stack[sp] = top.w;
                        sp++;
                    } else {
                        held++;
                    }
                    top = vec4<u32>(select(record.left, record.right, left_first), top.xyz);
                }
                node = select(record.right, record.left, left_first);
                continue;
            }
        } else {
            var i = (node & ~BVH_LEAF) / PRIMS_PER_TEXEL;
            var last = false;
            loop {
                let four = textureLoad(bvh_prims, texel(i));
                for (var c = 0u; c < PRIMS_PER_TEXEL; c++) {
                    let prim = texel_entry(four, c);
                    if (prim & PRIM_SPHERE) != 0u {
                        if sphere_blocks(prim & PRIM_INDEX, ray, t_max, start) {
                            return true;
                        }
                    } else if triangle_blocks(prim & PRIM_INDEX, ray, t_max, start) {
                        return true;
                    }
                    if (prim & PRIM_LAST) != 0u {
                        last = true;
                        break;
                    }
                }
                if last {
                    break;
                }
                i++;
            }
        }
        if held > 0u {
            node = top.x;
            top = top.yzwx;
            held--;
        } else if sp > 0u {
            sp--;
            node = stack[sp];
        } else {
            break;
        }
    }
    return false;
}

// The packet traversal (PACKET_TRAVERSAL): the active lanes of a subgroup
// walk the tree together, each testing its own ray against the children of
// one node, a node visited while any lane's ray enters it (Wald, Slusallek,
// Benthin and Wagner, "Interactive Rendering with Coherent Ray Tracing",
// 2001; on a GPU, Garanzha and Loop, "Fast Ray Sorting and Breadth-First
// Packet Traversal", 2010). Every choice is a vote of the lanes
// (subgroupAny, subgroupAdd), so the node index is the same in every lane,
// and the index popped from the stack is broadcast from the first lane
// (subgroupBroadcastFirst): NIR's divergence analysis then proves the
// record's address uniform and lavapipe loads it once for the SIMD group
// and broadcasts it (gallivm's emit_load_mem), where `bvh_record`'s texel
// loads load it once per lane.

// The lanes' vote on a node's children, `t` their entry distances (as
// child_entries): one subgroupAdd of four counts, a byte each (a subgroup
// has at most 128 lanes), since lavapipe reduces over the lanes in a loop
// for every subgroup operation. x: whether any lane enters the left child,
// y: the right; z: whether the left goes first, the child more lanes enter
// first (ties left).
fn packet_vote(t: vec2<f32>) -> vec3<bool> {
    let lanes = select(0u, 1u, t.x < BOX_MISS) | select(0u, 0x100u, t.y < BOX_MISS)
        | select(0u, 0x10000u, t.x < t.y) | select(0u, 0x1000000u, t.y < t.x);
    let counts = subgroupAdd(lanes);
    let byte = vec4<u32>(counts, counts >> 8u, counts >> 16u, counts >> 24u) & vec4<u32>(255u);
    return vec3<bool>(byte.x != 0u, byte.y != 0u, byte.z >= byte.w);
}

// bvh_closest for the lanes together. The same primitives are tested as by
// the per-lane walk (and more), so the nearest hit is the same but for
// exact ties of distance, which go to the primitive tested first.
fn bvh_closest_packet(ray: Ray, hit: ptr<function, Hit>) {
    let inv_dir = safe_inverse(ray.dir);
    // Nodes to visit (the same in every lane) and each lane's entry
    // distance, the newest in registers as in bvh_closest.
    var stack: array<u32, BVH_STACK>;
    var stack_t: array<f32, BVH_STACK>;
    var sp = 0u;
    var top = vec4<u32>();
    var top_t = vec4<f32>();
    var held = 0u;
    var node = 0u;
    var node_t = 0.0;
    loop {
        // An interior node is visited without asking whether any lane
        // still enters it: its children's box tests ask.
        if (node & BVH_LEAF) == 0u {
            let record = bvh_node_words[node];
            let t = child_entries(record, ray.origin, inv_dir, (*hit).t);
            let vote = packet_vote(t);
            if vote.x || vote.y {
                var left_first = vote.x;
                if vote.x && vote.y {
                    left_first = vote.z;
                    if held == STACK_REGISTERS {
                        stack[sp] = top.w;
                        stack_t[sp] = top_t.w;
                        sp++;
                    } else {
                        held++;
                    }
                    top = vec4<u32>(select(record.left, record.right, left_first), top.xyz);
                    top_t = vec4<f32>(select(t.x, t.y, left_first), top_t.xyz);
                }
                node = select(record.right, record.left, left_first);
                node_t = select(t.y, t.x, left_first);
                continue;
            }
        } else if subgroupAny(node_t < (*hit).t) {
            var i = node & ~BVH_LEAF;
            loop {
                let prim = bvh_prim_words[i];
                if (prim & PRIM_SPHERE) != 0u {
                    closest_sphere(prim & PRIM_INDEX, ray, hit);
                } else {
                    closest_triangle(prim & PRIM_INDEX, ray, hit);
                }
                if (prim & PRIM_LAST) != 0u {
                    break;
                }
                i++;
            }
        }
        if held > 0u {
            node = top.x;
            node_t = top_t.x;
            top = top.yzwx;
            top_t = top_t.yzwx;
            held--;
        } else if sp > 0u {
            sp--;
            node = stack[sp];
            node_t = stack_t[sp];
        } else {
            break;
        }
        node = subgroupBroadcastFirst(node);
    }
}

// bvh_occluded for the lanes together: a lane whose ray is blocked stops
// voting, and the walk ends when every lane's is.
fn bvh_occluded_packet(ray: Ray, t_max: f32, start: Hit) -> bool {
    let inv_dir = safe_inverse(ray.dir);
    var stack: array<u32, BVH_STACK>;
    var sp = 0u;
    var top = vec4<u32>();
    var held = 0u;
    var node = 0u;
    var blocked = false;
    loop {
        if (node & BVH_LEAF) == 0u {
            let record = bvh_node_words[node];
            var t = child_entries(record, ray.origin, inv_dir, t_max);
            if blocked {
                t = vec2<f32>(BOX_MISS);
            }
            let vote = packet_vote(t);
            if vote.x || vote.y {
                var left_first = vote.x;
                if vote.x && vote.y {
                    left_first = vote.z;
                    if held == STACK_REGISTERS {
                        stack[sp] = top.w;
                        sp++;
                    } else {
                        held++;
                    }
                    top = vec4<u32>(select(record.left, record.right, left_first), top.xyz);
                }
                node = select(record.right, record.left, left_first);
                continue;
            }
        } else {
            var i = node & ~BVH_LEAF;
            loop {
                let prim = bvh_prim_words[i];
                if !blocked {
                    if (prim & PRIM_SPHERE) != 0u {
                        blocked = sphere_blocks(prim & PRIM_INDEX, ray, t_max, start);
                    } else {
                        blocked = triangle_blocks(prim & PRIM_INDEX, ray, t_max, start);
                    }
                }
                if (prim & PRIM_LAST) != 0u {
                    break;
                }
                i++;
            }
            if subgroupAll(blocked) {
                return true;
            }
        }
        if held > 0u {
            node = top.x;
            top = top.yzwx;
            held--;
        } else if sp > 0u {
            sp--;
            node = stack[sp];
        } else {
            break;
        }
        node = subgroupBroadcastFirst(node);
    }
    return blocked;
}
