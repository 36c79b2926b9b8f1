// Directional, point and spot lights. The host pre-multiplies the diffuse and
// specular colours by the intensity; the ambient colour is not scaled.

const LIGHT_DIRECTIONAL: u32 = 0u;
const LIGHT_POINT: u32 = 1u;
const LIGHT_SPOT: u32 = 2u;

// Mirrored by render::layout::Light.
struct Light {
    position: vec3<f32>,
    kind: u32,
    // Direction the light travels (directional) or the cone axis (spot).
    direction: vec3<f32>,
    // KHR_lights_punctual cone: attenuation = clamp(cos * scale + offset, 0, 1)^2.
    cone_scale: f32,
    ambient: vec3<f32>,
    cone_offset: f32,
    diffuse: vec3<f32>,
    _pad0: u32,
    specular: vec3<f32>,
    _pad1: u32,
}

@group(0) @binding(5) var<storage, read> lights: array<Light>;

// What a light delivers at a point: the unit direction towards it, the
// distance a shadow ray must cover, and the falloff factor.
struct LightSample {
    to_light: vec3<f32>,
    distance: f32,
    falloff: f32,
}

fn sample_light(light: Light, p: vec3<f32>) -> LightSample {
    if HAS_DIRECTIONAL && light.kind == LIGHT_DIRECTIONAL {
        return LightSample(-light.direction, FAR, 1.0);
    }
    let d = light.position - p;
    let dist2 = dot(d, d);
    let dist = sqrt(dist2);
    // Inverse-square falloff; a point exactly at the light gets none.
    if dist2 == 0.0 {
        return LightSample(vec3<f32>(0.0, 0.0, 1.0), 0.0, 0.0);
    }
    let l = d / dist;
    var falloff = 1.0 / dist2;
    if HAS_SPOT && light.kind == LIGHT_SPOT {
        let a = clamp(dot(light.direction, -l) * light.cone_scale + light.cone_offset, 0.0, 1.0);
        falloff *= a * a;
    }
    return LightSample(l, dist, falloff);
}
