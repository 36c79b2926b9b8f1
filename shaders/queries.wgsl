// Ray queries: trace arbitrary rays and report the nearest hit, for tests of
// the intersection code (watertightness, grazing and degenerate cases) and
// for tools. Rays arrive camera-relative like everything else.

// Mirrored by render::layout::QueryRay. `dir` must have unit length.
struct QueryRay {
    origin: vec3<f32>,
    _pad0: u32,
    dir: vec3<f32>,
    _pad1: u32,
}

// Mirrored by render::layout::QueryHit. `t` < 0: no hit.
struct QueryHit {
    t: f32,
    kind: u32,
    index: u32,
    u: f32,
    v: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(11) var<storage, read> query_rays: array<QueryRay>;
@group(0) @binding(12) var<storage, read_write> query_hits: array<QueryHit>;

// One invocation per ray; push.size.x holds the number of rays.
@compute @workgroup_size(64, 1, 1)
fn trace(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (push.flags & FLAG_WARM_UP) != 0u || i >= push.size.x {
        return;
    }
    let q = query_rays[i];
    let hit = closest_hit(make_ray(q.origin, q.dir));
    var out = QueryHit(-1.0, KIND_NONE, 0u, 0.0, 0.0, 0u, 0u, 0u);
    if hit.found {
        let bary = select(vec2<f32>(0.0), hit.coords, hit.kind == KIND_TRIANGLE);
        out = QueryHit(hit.t, hit.kind, hit.index, bary.x, bary.y, 0u, 0u, 0u);
    }
    query_hits[i] = out;
}
