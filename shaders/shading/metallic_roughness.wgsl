// glTF 2.0's metallic-roughness BRDF, as the specification's Appendix B
// ("BRDF Implementation", glTF 2.0 specification 2.0.1, sections B.2 to
// B.3.5) defines it. A shader file like any user's
// (shading/interface.wgsl); the JSON type `metallic_roughness` and glTF
// materials map to it (src/scene/shading/metallic_roughness.rs has the
// same formulas in f64).
//
//   α = roughness²
//   D = α²·χ⁺(n·h) / (π·((n·h)²(α²−1)+1)²)                  (Trowbridge-Reitz)
//   V = χ⁺(h·l)·χ⁺(h·v) / ((|n·l| + √(α²+(1−α²)(n·l)²))·(|n·v| + √(α²+(1−α²)(n·v)²)))
//   specular = V·D
//   metal = specular·(c + (1−c)(1−|v·h|)⁵)
//   dielectric = mix(c/π, specular, 0.04 + 0.96(1−|v·h|)⁵)
//   f = mix(dielectric, metal, metallic)
//
// with c the base colour. A light sample adds f·(colour × intensity ×
// falloff)·(n·l), KHR_lights_punctual's units; the terms of f that carry
// c/π take the light's diffuse colour, the others its specular colour (the
// two are the same for glTF's lights). The model has no ambient term.
//
// Two limits where the formulas divide zero by zero are taken as 0: D at
// α = 0 (roughness 0, a mirror: a point light meets its delta lobe with
// probability zero) and V where both sums of its denominator are 0.

const PI: f32 = 3.14159265358979;

struct Params {
    base_colour: vec3<f32>,
    metallic: f32,
    roughness: f32,
    // Textures (0xffffffffu: none): the base colour's (sRGB), and the
    // metallic-roughness one (linear; B is metallic, G roughness).
    base_colour_texture: u32,
    metallic_roughness_texture: u32,
}

// Once per point: glTF's base colour is factor × texture × COLOR_0, and
// metallic and roughness are the factors times the texture's B and G.
fn prepare(s: Surface, p: Params) -> Params {
    var q = p;
    q.base_colour = p.base_colour * texture_at(p.base_colour_texture, s).rgb * s.colour.rgb;
    let mr = texture_at(p.metallic_roughness_texture, s);
    q.metallic = p.metallic * mr.b;
    q.roughness = p.roughness * mr.g;
    return q;
}

// χ⁺(x): 1 for x > 0, else 0.
fn chi_plus(x: f32) -> f32 {
    return select(0.0, 1.0, x > 0.0);
}

// The engine calls this only for samples with l·n > 0.
fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    let n = s.normal;
    let v = s.to_eye;
    let nl = dot(n, l.to_light);
    let nv = dot(n, v);
    let sum = l.to_light + v;
    let len2 = dot(sum, sum);
    // l = −v: no half vector; every χ⁺ of it is 0.
    var h = vec3<f32>(0.0);
    if len2 > 0.0 {
        h = sum * inverseSqrt(len2);
    }
    let nh = dot(n, h);
    let vh = dot(v, h);
    let lh = dot(l.to_light, h);
    let alpha = p.roughness * p.roughness;
    let a2 = alpha * alpha;
    let dd = nh * nh * (a2 - 1.0) + 1.0;
    var d = 0.0;
    if a2 > 0.0 && nh > 0.0 {
        d = a2 / (PI * dd * dd);
    }
    let vis_l = abs(nl) + sqrt(a2 + (1.0 - a2) * nl * nl);
    let vis_v = abs(nv) + sqrt(a2 + (1.0 - a2) * nv * nv);
    var vis = 0.0;
    if vis_l * vis_v > 0.0 {
        vis = chi_plus(lh) * chi_plus(vh) / (vis_l * vis_v);
    }
    let specular = vis * d;
    // |v·h| ≤ 1, but in f32 the dot of two unit vectors can round above 1
    // (l ≈ v, which the environment's lobes around the mirror direction
    // reach), and WGSL's pow of a negative base is NaN.
    let schlick = pow(max(0.0, 1.0 - abs(vh)), 5.0);
    let c = p.base_colour;
    let metal = specular * (c + (1.0 - c) * schlick);
    let fresnel = 0.04 + 0.96 * schlick;
    // mix(dielectric, metal, m), split into the part that takes the
    // light's diffuse colour and the part that takes its specular colour.
    let diffuse_part = (1.0 - p.metallic) * (1.0 - fresnel) * c / PI;
    let specular_part = (1.0 - p.metallic) * fresnel * specular + p.metallic * metal;
    return l.intensity * nl * (diffuse_part * l.diffuse + specular_part * l.specular);
}
