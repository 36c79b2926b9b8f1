// The shader interface: what the engine hands a shader file (the seminar's
// inputs of a shader: the point, its normal, the direction to the eye, the
// direction to the light, and the light's intensity and colours).
//
// A shader file defines
//   fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32>      (required)
//   fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32>   (optional)
//   fn prepare(s: Surface, p: Params) -> Params                        (optional)
//   struct Params { ... }                                              (optional)
// The colour at a point is the sum over lights of ambient(s, light.ambient, p)
// plus the sum of shade(s, l, p) over the light samples that are above the
// geometric surface and the shading normal and reach the point unoccluded,
// plus the material's emission. The engine makes those tests and traces the
// shadow rays itself. `prepare`, where defined, runs once per point before
// the others and gives the Params they receive: the place to sample
// textures once rather than once per light sample.
//
// A `u32` member of Params that the scene gives as {"texture": "file.png"}
// holds a texture; sample it with
//   texture_sample(t, uv) -> vec4<f32>   (linear RGBA at texture coordinates uv)
//   texture_at(t, s) -> vec4<f32>        (at the point, in the texture's own
//                                         coordinate set)
// filtered like the built-in shaders' textures, at the level of detail of the
// point (ray cones). A texture of 0xffffffffu gives (1, 1, 1, 1).
//
// Names a shader file must not declare: Surface, LightSample, texture_sample,
// texture_at, and every name that starts with `penumbra_` (the engine's own,
// see shaders/stages/shade.wgsl).

struct Surface {
    // World space (camera-relative: the camera sits at the origin).
    position: vec3<f32>,
    // Unit shading normal, facing the viewer.
    normal: vec3<f32>,
    // Unit geometric normal, facing the viewer.
    geometric_normal: vec3<f32>,
    // Unit vector towards the eye.
    to_eye: vec3<f32>,
    // Texture coordinates (TEXCOORD_0 of meshes, the planar coordinates of
    // planes, latitude-longitude of spheres; (0, 0) where a mesh has none).
    uv: vec2<f32>,
    // The second set of a mesh (TEXCOORD_1; (0, 0) where it has none).
    uv1: vec2<f32>,
    // The vertex colour, linear RGBA ((1, 1, 1, 1) without one).
    colour: vec4<f32>,
}

struct LightSample {
    // Unit vector towards the light (sample).
    to_light: vec3<f32>,
    // The light's intensity times its falloff at the point (times 1/N for one
    // of N area-light samples).
    intensity: f32,
    // The light's diffuse colour.
    diffuse: vec3<f32>,
    // The light's specular colour.
    specular: vec3<f32>,
}

// The level of detail of the point's texture coordinate sets 0 and 1 (set
// by the shade stage for each point).
var<private> penumbra_lod: vec2<f32>;

// Whether the scene samples any texture: the host resolves it per scene, so
// a shade pipeline of a scene without textures has no sampling code (it
// returns (1, 1, 1, 1), which is what no texture gives).
override penumbra_HAS_TEXTURES: bool = true;

fn texture_sample(t: u32, uv: vec2<f32>) -> vec4<f32> {
    if !penumbra_HAS_TEXTURES {
        return vec4<f32>(1.0);
    }
    return penumbra_texture_lod(t, uv, penumbra_lod[penumbra_texture_set(t)]);
}

fn texture_at(t: u32, s: Surface) -> vec4<f32> {
    if !penumbra_HAS_TEXTURES {
        return vec4<f32>(1.0);
    }
    let uv_set = penumbra_texture_set(t);
    return penumbra_texture_lod(t, select(s.uv, s.uv1, uv_set == 1u), penumbra_lod[uv_set]);
}
