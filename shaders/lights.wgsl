// Directional, point and spot lights, area lights (rectangle, sphere) and
// the environment (docs/materials.md, "Environment").
// A light has an intensity and ambient, diffuse and specular colours; the
// shade stage hands a shader the intensity times the falloff
// (shaders/shading/interface.wgsl: LightSample), and the ambient colour
// unscaled.
//
// An area light of intensity I is the limit of N point lights of intensity
// I/N spread uniformly over its surface (for the rectangle each weighted by
// the emitter's cosine); the kernel takes `samples` of them per pass.

const LIGHT_DIRECTIONAL: u32 = 0u;
const LIGHT_POINT: u32 = 1u;
const LIGHT_SPOT: u32 = 2u;
const LIGHT_RECT: u32 = 3u;
const LIGHT_SPHERE: u32 = 4u;
// Sampled before the area kinds (which are every kind >= LIGHT_RECT).
const LIGHT_ENVIRONMENT: u32 = 5u;

// Mirrored by render::layout::Light.
struct Light {
    // Point and spot: position; rectangle: corner; sphere: centre.
    position: vec3<f32>,
    kind: u32,
    // Direction the light travels (directional), the cone axis (spot),
    // the emitting side's unit normal (rectangle), or up (environment).
    direction: vec3<f32>,
    // KHR_lights_punctual cone: attenuation = clamp(cos * scale + offset, 0, 1)^2.
    // Environment: the gradient g(u) = cone_offset + cone_scale * u.
    cone_scale: f32,
    ambient: vec3<f32>,
    cone_offset: f32,
    diffuse: vec3<f32>,
    // Samples per pass (1 for punctual lights).
    samples: u32,
    specular: vec3<f32>,
    // Sphere light radius.
    radius: f32,
    // Rectangle edges.
    edge1: vec3<f32>,
    intensity: f32,
    edge2: vec3<f32>,
    _pad1: u32,
}

@group(0) @binding(5) var<storage, read> lights: array<Light>;
// The first UNIFORM_LIGHTS lights again, as a uniform buffer
// (render::layout::light_block): lavapipe loads a uniform buffer at an
// address that is the same for every lane with one scalar load, also in
// loops and branches, where its storage-buffer load is a loop over the
// lanes (docs/stages.md measures the difference). Each component of such a
// load is still a bounds check and a branch, so the first light, which the
// stages read before any branch, comes from `lights` (first_light).
const UNIFORM_LIGHTS: u32 = 128u;
@group(0) @binding(28) var<uniform> light_block: array<Light, UNIFORM_LIGHTS>;

// Light `i`, for the light loops (after first_light).
fn light_at(i: u32) -> Light {
    if i < UNIFORM_LIGHTS {
        return light_block[i];
    }
    return lights[i];
}

// lights[0], read by the shadow stage's first statement. lavapipe loads data at a
// uniform address once per SIMD group only outside all branches and loops;
// inside them every lane loads for itself, and the light loop is inside
// both (0.95x the bunny frame: docs/bench.md §6). The host always uploads at
// least one light, so this read is in bounds.
var<private> first_light: Light;

// What a light delivers at a point: the unit direction towards it, the
// distance a shadow ray must cover, and the falloff factor.
struct SampledLight {
    to_light: vec3<f32>,
    distance: f32,
    falloff: f32,
}

// How many samples a light takes per pass.
fn light_sample_count(light: Light) -> u32 {
    if HAS_AREA_LIGHTS {
        return light.samples;
    }
    return 1u;
}

// Sample `uv` in [0, 1)² of light `light` as seen from `p`, a point with
// unit shading normal `n` seen from the unit direction `v` (towards the eye;
// only the environment's samples depend on the two: environment.wgsl). For
// area lights the falloff includes the 1/N of each of the N point lights.
fn sample_light(light: Light, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, uv: vec2<f32>) -> SampledLight {
    if HAS_DIRECTIONAL && light.kind == LIGHT_DIRECTIONAL {
        return SampledLight(-light.direction, FAR, 1.0);
    }
    if HAS_AREA_LIGHTS && light.kind == LIGHT_ENVIRONMENT {
        return sample_environment(light, n, v, uv);
    }
    if HAS_AREA_LIGHTS && light.kind >= LIGHT_RECT {
        var x: vec3<f32>;
        if light.kind == LIGHT_RECT {
            x = light.position + uv.x * light.edge1 + uv.y * light.edge2;
        } else {
            // Uniform on the sphere: z uniform in [-1, 1], azimuth uniform.
            let z = 1.0 - 2.0 * uv.x;
            let r = sqrt(max(0.0, 1.0 - z * z));
            let phi = 6.283185307 * uv.y;
            x = light.position + light.radius * vec3<f32>(r * cos(phi), r * sin(phi), z);
        }
        let d = x - p;
        let dist2 = dot(d, d);
        if dist2 == 0.0 {
            return SampledLight(vec3<f32>(0.0, 0.0, 1.0), 0.0, 0.0);
        }
        let dist = sqrt(dist2);
        let l = d / dist;
        var falloff = 1.0 / (dist2 * f32(light.samples));
        if light.kind == LIGHT_RECT {
            falloff *= max(0.0, dot(light.direction, -l));
        }
        return SampledLight(l, dist, falloff);
    }
    let d = light.position - p;
    let dist2 = dot(d, d);
    let dist = sqrt(dist2);
    // Inverse-square falloff; a point exactly at the light gets none.
    if dist2 == 0.0 {
        return SampledLight(vec3<f32>(0.0, 0.0, 1.0), 0.0, 0.0);
    }
    let l = d / dist;
    var falloff = 1.0 / dist2;
    if HAS_SPOT && light.kind == LIGHT_SPOT {
        let a = clamp(dot(light.direction, -l) * light.cone_scale + light.cone_offset, 0.0, 1.0);
        falloff *= a * a;
    }
    return SampledLight(l, dist, falloff);
}
