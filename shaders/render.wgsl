// penumbra's compute kernel: one invocation per pixel.
// The host concatenates the files of this tree (see src/render/compile.rs);
// WGSL declarations are order-independent, so each concept file declares its
// own data layout, binding and functions.
//
// All positions arrive camera-relative (the host subtracts the eye position in
// f64 before rounding to f32), so the camera sits at the origin and precision
// does not fall off far from the world origin.

// Features of the scene; the host resolves these per scene with naga's
// process_overrides, and lavapipe's compiler drops the code of every kind the
// scene does not use.
override HAS_PLANES: bool = true;
override HAS_SPHERES: bool = true;
override HAS_TRIANGLES: bool = true;
override HAS_VERTEX_NORMALS: bool = true;
override HAS_DIRECTIONAL: bool = true;
override HAS_POINT: bool = true;
override HAS_SPOT: bool = true;
override HAS_PHONG: bool = true;
override HAS_BLINN_PHONG: bool = true;
override HAS_CHECKER: bool = true;
// Kernel variants chosen by the user (render::KernelOptions).
override USE_BVH: bool = true;
override TRIANGLE_TEST: u32 = 0u;
// 0: robust shadow-ray start (shadows.wgsl); > 0: fixed offset along the normal.
override SHADOW_EPSILON: f32 = 0.0;
// Sampling (compiled in only for scenes with area lights or several samples
// per pixel): which sampler, area lights, pixel jitter.
override SAMPLER: u32 = 0u;
override HAS_AREA_LIGHTS: bool = true;
override PIXEL_JITTER: bool = true;
// Arbitrary output variables (depth, normal, uv, ids) requested.
override HAS_AOV: bool = true;

// Mirrored by render::layout::Globals.
struct Globals {
    camera: Camera,
    background: vec3<f32>,
    num_planes: u32,
    num_spheres: u32,
    num_triangles: u32,
    num_lights: u32,
    num_shaders: u32,
    num_bvh_nodes: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// Mirrored by render::layout::PushConstants.
struct PushConstants {
    // Pixel offset of this dispatch (tiling), and the image size in pixels
    // (at most the uploaded image's; smaller for previews).
    origin: vec2<u32>,
    size: vec2<u32>,
    flags: u32,
    // Progressive rendering: which pass this is (pass 0 overwrites the
    // image, later passes add to it; the host divides by the pass count).
    pass_index: u32,
    // Seed of every random choice.
    seed: u32,
    // Index of the first pixel the image buffer holds: 0, or the first pixel
    // of the band of rows that one part of a split render holds
    // (`render --tile`), so that a tile needs a buffer of its own size only.
    slot_base: u32,
}

const FLAG_WARM_UP: u32 = 1u;
// This pass overwrites the image even if its pass_index is not 0: the first
// pass of a sample split (`render --passes A..B`) that starts at A > 0.
const FLAG_FRESH: u32 = 2u;

@group(0) @binding(0) var<uniform> globals: Globals;
// Linear RGB; alpha is 1 where a primary ray hit something, else 0.
@group(0) @binding(7) var<storage, read_write> image: array<vec4<f32>>;
// [0] primary rays, [1] shadow rays traced.
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>, 2>;
var<immediate> push: PushConstants;

@compute @workgroup_size(8, 8, 1)
fn render(@builtin(global_invocation_id) gid: vec3<u32>) {
    // Before any branch (see first_light).
    first_light = lights[0];
    // The warm-up dispatch makes the driver compile the kernel (lavapipe
    // compiles at the first dispatch) without rendering anything.
    if (push.flags & FLAG_WARM_UP) != 0u {
        return;
    }
    let px = gid.xy + push.origin;
    var shadow_rays = 0u;
    var primary = 0u;
    if px.x < push.size.x && px.y < push.size.y {
        let pixel = px.y * push.size.x + px.x;
        // One sample per pass: the pixel centre, or a stratified point in the
        // pixel (box filter) when several samples per pixel are asked for.
        var sub = vec2<f32>(0.5);
        if PIXEL_JITTER {
            sub = sample_2d(pixel, 0u, push.pass_index);
        }
        let ray = primary_ray(globals.camera, px, push.size, sub);
        let hit = closest_hit(ray);
        var colour = globals.background;
        var alpha = 0.0;
        if hit.found {
            colour = shade(ray, hit, pixel, &shadow_rays);
            alpha = 1.0;
        }
        if HAS_AOV && push.pass_index == 0u {
            write_aov(pixel, hit);
        }
        var value = vec4<f32>(colour, alpha);
        if push.pass_index > 0u && (push.flags & FLAG_FRESH) == 0u {
            value += image[pixel - push.slot_base];
        }
        image[pixel - push.slot_base] = value;
        primary = 1u;
    }
    // One global atomic per subgroup instead of one per pixel. (Summing
    // per workgroup needs a barrier, and lavapipe then runs the whole kernel
    // as coroutines: docs/bench.md §6 measures the difference.)
    let subgroup_primary = subgroupAdd(primary);
    let subgroup_shadow = subgroupAdd(shadow_rays);
    // The first active lane of the subgroup (naga has no subgroupElect).
    if subgroupExclusiveAdd(1u) == 0u {
        atomicAdd(&counters[0], subgroup_primary);
        atomicAdd(&counters[1], subgroup_shadow);
    }
}
