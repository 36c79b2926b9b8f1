// KHR_materials_pbrSpecularGlossiness (glTF 2.0 extension, archived;
// "Specular - Glossiness" section): its BRDF inputs
//   c_diff = diffuse.rgb·(1 − max(specular.r, specular.g, specular.b))
//   F0     = specular
//   α      = (1 − glossiness)²
// in the BRDF of the glTF 2.0 specification's Appendix B with Schlick's
// Fresnel of F0 (shading/metallic_roughness.wgsl has the same D and V):
//   F = F0 + (1 − F0)(1 − |v·h|)⁵
//   f = (1 − F)·c_diff/π + F·V·D
// A shader file like any user's (shading/interface.wgsl); glTF materials
// with the extension map to it (src/scene/shading/specular_glossiness.rs
// has the same formulas in f64). A light sample adds f·(colour ×
// intensity × falloff)·(n·l); the c_diff/π term takes the light's diffuse
// colour, the F·V·D term its specular colour.

const PI: f32 = 3.14159265358979;

struct Params {
    diffuse: vec3<f32>,
    specular: vec3<f32>,
    glossiness: f32,
    // Textures (0xffffffffu: none): the diffuse one (sRGB), and the
    // specular-glossiness one (specular in sRGB RGB, glossiness in linear A).
    diffuse_texture: u32,
    specular_glossiness_texture: u32,
}

// Once per point: the factors times their textures; COLOR_0 scales diffuse.
fn prepare(s: Surface, p: Params) -> Params {
    var q = p;
    q.diffuse = p.diffuse * texture_at(p.diffuse_texture, s).rgb * s.colour.rgb;
    let sg = texture_at(p.specular_glossiness_texture, s);
    q.specular = p.specular * sg.rgb;
    q.glossiness = p.glossiness * sg.a;
    return q;
}

// The engine calls this only for samples with l·n > 0.
fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    let n = s.normal;
    let v = s.to_eye;
    let nl = dot(n, l.to_light);
    let nv = dot(n, v);
    let sum = l.to_light + v;
    let len2 = dot(sum, sum);
    var h = vec3<f32>(0.0);
    if len2 > 0.0 {
        h = sum * inverseSqrt(len2);
    }
    let nh = dot(n, h);
    let vh = dot(v, h);
    let lh = dot(l.to_light, h);
    let alpha = (1.0 - p.glossiness) * (1.0 - p.glossiness);
    let a2 = alpha * alpha;
    let dd = nh * nh * (a2 - 1.0) + 1.0;
    var d = 0.0;
    if a2 > 0.0 && nh > 0.0 {
        d = a2 / (PI * dd * dd);
    }
    let vis_l = abs(nl) + sqrt(a2 + (1.0 - a2) * nl * nl);
    let vis_v = abs(nv) + sqrt(a2 + (1.0 - a2) * nv * nv);
    var vis = 0.0;
    if vis_l * vis_v > 0.0 && lh > 0.0 && vh > 0.0 {
        vis = 1.0 / (vis_l * vis_v);
    }
    // max: |v·h| can round above 1 in f32, and pow of a negative base is NaN.
    let f = p.specular + (1.0 - p.specular) * pow(max(0.0, 1.0 - abs(vh)), 5.0);
    let c_diff = p.diffuse * (1.0 - max(p.specular.r, max(p.specular.g, p.specular.b)));
    let diffuse_part = (1.0 - f) * c_diff / PI;
    let specular_part = f * vis * d;
    return l.intensity * nl * (diffuse_part * l.diffuse + specular_part * l.specular);
}
