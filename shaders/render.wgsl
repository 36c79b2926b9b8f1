// What every engine stage shares: the scene's feature overrides, the
// globals, the push constants and the ray counters. The renderer runs a
// frame as a chain of stages (shaders/stages/, after pbrt-v4's wavefront
// integrator); each stage is its own module, concatenated by the host from
// the files it needs (src/render/stages.rs). WGSL declarations are
// order-independent, so each concept file declares its own data layout,
// binding and functions.
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
override HAS_CHECKER: bool = true;
// Textures (scene::Features): level of detail, vertex attributes, normal
// maps, alpha cut-outs in traversal.
override HAS_TEXTURES: bool = true;
override HAS_ATTRIBUTES: bool = true;
override HAS_NORMAL_MAPS: bool = true;
override HAS_ALPHA_TESTS: bool = true;
// Some triangle is single-sided (glTF `doubleSided: false`): camera rays
// skip its back face (hit.wgsl, faces_the_ray).
override HAS_SINGLE_SIDED: bool = true;
// Kernel variants chosen by the user (render::KernelOptions).
override USE_BVH: bool = true;
// The lanes of a subgroup walk the BVH together (render::Traversal::Packet;
// bvh.wgsl, bvh_closest_packet), else each its own ray's path.
override PACKET_TRAVERSAL: bool = false;
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
// One chunk holds every light sample of a pixel: the hit stage traces the
// shadow rays itself and the shadow stage does not run (stages/shadow.wgsl).
override FUSED_SHADOWS: bool = true;
// The stages write their hit records and queue as storage-buffer words over
// the memory of the texel images the next stage reads (a CPU device:
// vulkan::Context::stage_words, where a texel store costs several buffer
// stores), rather than with textureStore.
override STAGE_WORDS: bool = false;
// A stage invocation's place in its workgroup's 8×8 block of pixels comes
// from its subgroup and lane (vulkan::Context::lane_pixels: a CPU device,
// whose subgroups fill a workgroup in order), not from
// local_invocation_index. lavapipe computes the local invocation ids of
// every lane with integer divisions by the workgroup's size, a runtime
// value there, at the start of every SIMD group; the subgroup ids cost it
// nothing (docs/stages.md).
override LANE_PIXELS: bool = false;

// A texel's four words as the two 64-bit words (low word first: the same
// bytes) that the stages store with STAGE_WORDS. lavapipe stores a vector
// at a per-lane address one component at a time, each with a bounds check
// and a branch, so two 64-bit components cost less than four 32-bit ones
// (docs/stages.md).
fn stage_words(v: vec4<u32>) -> vec2<u64> {
    return vec2<u64>(u64(v.x) | (u64(v.y) << 32u), u64(v.z) | (u64(v.w) << 32u));
}

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

// Mirrored by render::layout::PushConstants. One block for every stage
// (shaders/stages/); each reads the members it needs.
struct PushConstants {
    // Pixel offset of this dispatch (a band of the tile), and the image size
    // in pixels (at most the uploaded image's; smaller for previews).
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
    // The tile whose hit records and queue the stage buffers hold: its first
    // pixel and its width (stages/records.wgsl).
    tile_origin: vec2<u32>,
    tile_width: u32,
    // Shade stage: the shader program this dispatch runs.
    program: u32,
    // Light-sample queue: the first light sample of this chunk, and how many
    // the queue holds per pixel (stages/records.wgsl).
    sample_first: u32,
    sample_count: u32,
    // Lights in the scene (globals.num_lights; the shade stage sees no
    // globals).
    light_count: u32,
    _pad0: u32,
}

const FLAG_WARM_UP: u32 = 1u;
// This pass overwrites the image even if its pass_index is not 0: the first
// pass of a sample split (`render --passes A..B`) that starts at A > 0.
const FLAG_FRESH: u32 = 2u;
// This dispatch shades the last chunk of light samples: the shade stage
// writes the pixel's colour to the image (earlier chunks sum in `radiance`).
const FLAG_LAST_CHUNK: u32 = 4u;
// The shade stage interpolates triangles' vertex attributes
// (attributes.wgsl); it adds the objects' emission (surface_maps.wgsl).
const FLAG_ATTRIBUTES: u32 = 8u;
const FLAG_EMISSION: u32 = 16u;
// The shade stage reads triangles' vertex colours (some mesh has them).
const FLAG_COLOURS: u32 = 32u;

// Farther than anything in a scene; used as "no hit yet" and as the length
// of shadow rays towards directional lights.
const FAR: f32 = 3.0e38;

@group(0) @binding(0) var<uniform> globals: Globals;
// [0] primary rays, [1] shadow rays traced.
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>, 2>;
var<immediate> push: PushConstants;

// Where a stage invocation is: the stages run workgroups of 64 invocations
// in one dimension, one 8×8 block of pixels each (render::TILE); subgroup
// ids need a one-dimensional workgroup. Each stage's entry point takes
// these builtins as arguments of its own: as members of a struct argument
// (naga 30, Mesa 25.0.7) the shade stage placed only every eighth row.
struct StageInvocation {
    workgroup: vec3<u32>,
    index: u32,
    subgroup: u32,
    subgroup_size: u32,
    lane: u32,
}

// The pixel of this invocation (its dispatch covers a band of the tile):
// its block's, and in the block row by row by its index (LANE_PIXELS says
// which index).
fn stage_pixel(inv: StageInvocation) -> vec2<u32> {
    var index = inv.index;
    if LANE_PIXELS {
        index = inv.subgroup * inv.subgroup_size + inv.lane;
    }
    let block = inv.workgroup.xy * 8u + push.origin;
    return block + vec2<u32>(index & 7u, index >> 3u);
}

// Whether a pixel lies in the image.
fn in_image(px: vec2<u32>) -> bool {
    return px.x < push.size.x && px.y < push.size.y;
}

// Adds this invocation's `count` to counter `which` with one global atomic
// per subgroup instead of one per invocation. (Summing per workgroup needs a
// barrier, and lavapipe then runs the whole kernel as coroutines:
// docs/bench.md §6 measures the difference.)
fn count_rays(which: u32, count: u32) {
    let total = subgroupAdd(count);
    // The first active lane of the subgroup (naga has no subgroupElect).
    if subgroupExclusiveAdd(1u) == 0u {
        atomicAdd(&counters[which], total);
    }
}
