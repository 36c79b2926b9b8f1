// Hit records and the light-sample queue: what the stages of a frame pass
// each other, for one tile of the image (the host sizes the buffers per
// tile within a memory bound: src/render/tiles.rs).
//
// Pixel `px` of the tile has record `tile_slot(px)`; light sample `k` of the
// pixel (lights in scene order, each light's samples in turn) has queue
// entry `tile_slot(px) * push.sample_count + (k - push.sample_first)`, for
// the samples of the chunk the queue holds.

// The kinds of primitive a ray can hit.
const KIND_PLANE: u32 = 0u;
const KIND_SPHERE: u32 = 1u;
const KIND_TRIANGLE: u32 = 2u;
// A hit that matches no primitive: the ray hit nothing.
const KIND_NONE: u32 = 0xffffffffu;

// Mirrored by render::layout::HitRecord (and by penumbra_HitRecord in
// stages/shade.wgsl, which a shader file is compiled with).
struct HitRecord {
    position: vec3<f32>,
    // Distance along the primary ray.
    t: f32,
    // Unit, facing the viewer.
    geometric_normal: vec3<f32>,
    // Primitive kind (hit.wgsl); KIND_NONE where the ray hit nothing.
    kind: u32,
    // Unit, facing the viewer.
    shading_normal: vec3<f32>,
    // Index among the primitives of its kind.
    index: u32,
    to_eye: vec3<f32>,
    object: u32,
    // Texture coordinates ((0, 0) where the primitive has none).
    uv: vec2<f32>,
    // Barycentric u, v of triangle hits.
    bary: vec2<f32>,
    // The scene's shader at the hit; after material resolve the leaf shader
    // (checkers resolved), its program and the offset of its parameters.
    shader: u32,
    program: u32,
    params: u32,
    _pad: u32,
}

@group(0) @binding(14) var<storage, read_write> hit_records: array<HitRecord>;
// Queued shadow rays: (unit direction to the light, distance to it).
@group(0) @binding(15) var<storage, read_write> queue_rays: array<vec4<f32>>;
// Each queued sample's light: (falloff at the point, the light's index as
// bits). Falloff 0 where the sample is below the surface or occluded:
// nothing to add.
@group(0) @binding(16) var<storage, read_write> queue_samples: array<vec2<f32>>;
// Per tile pixel: the colour the shade stage sums.
@group(0) @binding(17) var<storage, read_write> radiance: array<vec4<f32>>;

fn tile_slot(px: vec2<u32>) -> u32 {
    let local = px - push.tile_origin;
    return local.y * push.tile_width + local.x;
}
