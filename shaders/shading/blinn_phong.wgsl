// Blinn-Phong (Blinn 1977): Phong's terms with the half-vector lobe
// max(0, h·n)^n_s, h = normalize(l + v). A shader file like any user's
// (shading/interface.wgsl); the JSON type `blinn_phong` maps to it.

struct Params {
    ambient: vec3<f32>,
    diffuse: vec3<f32>,
    specular: vec3<f32>,
    shininess: f32,
    // Textures that scale the reflectances (0xffffffffu: none).
    ambient_texture: u32,
    diffuse_texture: u32,
    specular_texture: u32,
}

// Once per point: the textures and the vertex colour scale the
// reflectances (glTF's base colour is factor × texture × COLOR_0).
fn prepare(s: Surface, p: Params) -> Params {
    var q = p;
    q.ambient = p.ambient * texture_at(p.ambient_texture, s).rgb;
    q.diffuse = p.diffuse * texture_at(p.diffuse_texture, s).rgb * s.colour.rgb;
    q.specular = p.specular * texture_at(p.specular_texture, s).rgb;
    return q;
}

fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32> {
    return p.ambient * light_ambient;
}

// The engine calls this only for samples with l·n > 0.
fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    let ln = dot(l.to_light, s.normal);
    let sum = l.to_light + s.to_eye;
    let len2 = dot(sum, sum);
    // l = -v: no half vector; the lobe is 0^n_s (1 for n_s = 0).
    var cos_h = 0.0;
    if len2 > 0.0 {
        cos_h = max(dot(sum * inverseSqrt(len2), s.normal), 0.0);
    }
    var lobe = 1.0;
    if p.shininess != 0.0 {
        lobe = select(0.0, pow(cos_h, p.shininess), cos_h > 0.0);
    }
    return l.intensity * (p.diffuse * l.diffuse * ln + p.specular * l.specular * lobe);
}
