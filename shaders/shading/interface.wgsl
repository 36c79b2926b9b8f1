// The shader interface: what the engine hands a shader file (the seminar's
// inputs of a shader: the point, its normal, the direction to the eye, the
// direction to the light, and the light's intensity and colours).
//
// A shader file defines
//   fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32>      (required)
//   fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32>   (optional)
//   struct Params { ... }                                              (optional)
// The colour at a point is the sum over lights of ambient(s, light.ambient, p)
// plus the sum of shade(s, l, p) over the light samples that are above the
// geometric surface and the shading normal and reach the point unoccluded.
// The engine makes those tests and traces the shadow rays itself.
//
// Names a shader file must not declare: Surface, LightSample, and every name
// that starts with `penumbra_` (the engine's own, see shaders/stages/shade.wgsl).

struct Surface {
    // World space (camera-relative: the camera sits at the origin).
    position: vec3<f32>,
    // Unit shading normal, facing the viewer.
    normal: vec3<f32>,
    // Unit geometric normal, facing the viewer.
    geometric_normal: vec3<f32>,
    // Unit vector towards the eye.
    to_eye: vec3<f32>,
    // Texture coordinates; (0, 0) where the primitive has none.
    uv: vec2<f32>,
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
