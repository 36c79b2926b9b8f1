// Hit records and the light-sample queue: what the stages of a frame pass
// each other, for one tile of the image (the host sizes them per tile within
// a memory bound: src/render/tiles.rs). They are texel images, not storage
// buffers: lavapipe loads a storage buffer at a per-lane address as a loop
// over the SIMD lanes, while a texel load is straight-line SIMD code
// (texels.wgsl), which also makes the stages faster to compile.
//
// Pixel `px` of the tile has record `tile_slot(px)`; light sample `k` of the
// pixel (lights in scene order, each light's samples in turn) has queue
// entry `tile_slot(px) * push.sample_count + (k - push.sample_first)`, for
// the samples of the chunk the queue holds.
//
// Slots go block by block: the 64 pixels of each 8×8 block of the tile (one
// workgroup of every stage) are 64 consecutive slots, the blocks in
// row-major order. A workgroup then reads and writes one contiguous run of
// records instead of eight rows a tile row apart, which the cores' prefetch
// follows (docs/stages.md measures it). The tile width is a multiple of 8
// (tiles::TilePlan), so the slots stay below the tile's pixel count. The
// shade stage computes the same slot (stages/shade.wgsl); if the two
// disagreed, every image test would see the wrong records.

// The kinds of primitive a ray can hit.
const KIND_PLANE: u32 = 0u;
const KIND_SPHERE: u32 = 1u;
const KIND_TRIANGLE: u32 = 2u;
// A hit that matches no primitive: the ray hit nothing.
const KIND_NONE: u32 = 0xffffffffu;

// A hit record (render::layout::RECORD_TEXELS texels at binding 14):
//   0: position (camera-relative), then the kind and the scene object in
//      one word, `record_kind_object` (KIND_NONE: the ray hit nothing)
//   1: unit geometric normal facing the viewer, primitive index
//   2: unit shading normal facing the viewer, the scene's shader
//   3: triangles: the barycentrics (u, v), which the shade stage
//      interpolates vertex attributes with; planes and spheres: their
//      texture coordinates (surface.wgsl); then the geometric level of
//      detail of texture coordinate sets 0 and 1 (0 without textures);
//      written and read only where `record_coords()`
// The direction to the eye is not stored: the camera sits at the origin,
// so the shade stage takes it from the position (or, for an orthographic
// camera, the view direction). A texel fewer to store and load saved
// 1.4 % of the bunny frame (docs/stages.md).
const RECORD_TEXELS: u32 = 4u;
// The kind is the word's low KIND_BITS bits and the object the rest, so a
// scene has at most 2^30 objects (render::MAX_OBJECTS). No hit has all
// bits set: the kinds are 0 to 2.
const KIND_BITS: u32 = 2u;

fn record_kind_object(kind: u32, object: u32) -> u32 {
    return kind | (object << KIND_BITS);
}

// The kind in a record's word 0.w: KIND_NONE where the ray hit nothing.
// (The shade stage decodes the word itself: stages/shade.wgsl.)
fn record_kind(word: u32) -> u32 {
    return select(word & ((1u << KIND_BITS) - 1u), KIND_NONE, word == KIND_NONE);
}

// Whether the records' texel 3 is needed: a scene of triangles without
// vertex attributes or textures has texture coordinates (0, 0) everywhere
// and no level of detail to use, so its hit stage stores no texel 3 and
// its shade stage loads none (the shade stage's penumbra_record_coords is
// the same test of the same features).
fn record_coords() -> bool {
    return HAS_PLANES || HAS_SPHERES || HAS_ATTRIBUTES || HAS_TEXTURES;
}
// Material resolve's result (1 texel a record at binding 16), written only
// when the scene has checkers (without them the shade stage reads the hit's
// shader from the shader table): the leaf shader, its program, the first of
// its parameter words, 0.
// A queue entry (render::layout::QUEUE_TEXELS texels at binding 15):
//   0: unit direction to the light, falloff at the point (0: below the
//      surface or occluded, nothing to add)
// Which light a sample belongs to follows from its index (lights in scene
// order, each light's samples in turn), so the entry does not hold it.
const QUEUE_TEXELS: u32 = 1u;

// The records, for the stages that read them (the hit stage writes them as
// `hit_records_out`: a stage that writes a stage image names it `<name>_out`).
@group(0) @binding(14) var hit_records: texture_storage_2d<rgba32uint, read>;

// Per tile pixel: the colour the shade stage sums.
@group(0) @binding(17) var<storage, read_write> radiance: array<vec4<f32>>;

fn tile_slot(px: vec2<u32>) -> u32 {
    let local = px - push.tile_origin;
    let block = (local.y >> 3u) * (push.tile_width >> 3u) + (local.x >> 3u);
    return (block << 6u) | ((local.y & 7u) << 3u) | (local.x & 7u);
}

// Texel `i` of record `slot`.
fn record_texel(slot: u32, i: u32) -> vec2<u32> {
    return texel(slot * RECORD_TEXELS + i);
}

// Texel `i` of queue entry `entry`.
fn queue_texel(entry: u32, i: u32) -> vec2<u32> {
    return texel(entry * QUEUE_TEXELS + i);
}
