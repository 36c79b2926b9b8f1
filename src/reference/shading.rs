//! Shading as `shaders/shading/`: nested checkers resolved to a Phong,
//! Blinn-Phong or metallic-roughness node, and the seminar's sum over
//! lights and light samples (`shade`).

use glam::DVec3;

use super::hit::Hit;
use super::intersect::Ray;
use super::lights::sample_light;
use super::sampling::sample_2d;
use super::shadows::occluded;
use super::surface::AlphaRay;
use super::World;
use crate::scene::shading::{metallic_roughness, specular_glossiness};
use crate::scene::{MetallicRoughness, PhongTextures, Shader, SpecularGlossiness};

/// The lookup point of a checker moves this many cells into the surface
/// (away from the viewer), so a surface on a cell boundary picks one cell
/// consistently (`CHECKER_INSET`).
const CHECKER_INSET: f64 = 1e-3;

/// Whether checker cell of `p` is even: `floor(p/size − inset·n)` summed
/// over the axes. `n` is the geometric normal facing the viewer. (The GPU
/// computes the same in camera-relative coordinates with the eye's cell
/// offset and parity added back.)
fn checker_is_even(size: f64, p: DVec3, n: DVec3) -> bool {
    let cell = (p / size - CHECKER_INSET * n).floor();
    (cell.x + cell.y + cell.z).rem_euclid(2.0) == 0.0
}

/// A Phong or Blinn-Phong node, in `f64`, or a metallic-roughness one
/// (`pbr`; the Phong fields are then zero).
#[derive(Clone, Copy, Debug)]
pub struct Lobe {
    /// glTF's metallic-roughness BRDF instead of the Phong terms.
    pub pbr: Option<MetallicRoughness>,
    /// KHR_materials_pbrSpecularGlossiness instead of the Phong terms.
    pub sg: Option<SpecularGlossiness>,
    /// Blinn-Phong (half vector) rather than Phong (mirror direction).
    pub blinn: bool,
    /// k_a.
    pub ambient: DVec3,
    /// k_d.
    pub diffuse: DVec3,
    /// k_s.
    pub specular: DVec3,
    /// n_s.
    pub shininess: f64,
    /// The textures that scale k_a, k_d and k_s.
    pub textures: PhongTextures,
}

/// Walks down nested checkers to the shading model at `p` (`resolve_shader`;
/// the depth bound is the number of shaders, as on the GPU).
pub fn resolve_shader(shaders: &[Shader], id: u32, p: DVec3, n: DVec3) -> Lobe {
    let mut node = &shaders[id as usize];
    for _ in 0..shaders.len() {
        let Shader::Checker(c) = node else { break };
        let next = if checker_is_even(c.size, p, n) {
            c.even
        } else {
            c.odd
        };
        node = &shaders[next];
    }
    match node {
        Shader::MetallicRoughness(m) => Lobe {
            pbr: Some(*m),
            ..NONE
        },
        Shader::SpecularGlossiness(m) => Lobe {
            sg: Some(*m),
            ..NONE
        },
        Shader::Phong(m) | Shader::BlinnPhong(m) => Lobe {
            pbr: None,
            sg: None,
            blinn: matches!(node, Shader::BlinnPhong(_)),
            ambient: m.ambient.as_dvec3(),
            diffuse: m.diffuse.as_dvec3(),
            specular: m.specular.as_dvec3(),
            shininess: m.shininess as f64,
            textures: m.textures,
        },
        // Only a cyclic table (which validation rules out) ends here; the
        // GPU would read the checker node's zero colours. A WGSL shader never
        // gets here: `reference::render` refuses such a scene first.
        Shader::Checker(_) | Shader::Wgsl(_) => NONE,
    }
}

/// A node that adds nothing.
const NONE: Lobe = Lobe {
    pbr: None,
    sg: None,
    blinn: false,
    ambient: DVec3::ZERO,
    diffuse: DVec3::ZERO,
    specular: DVec3::ZERO,
    shininess: 0.0,
    textures: PhongTextures {
        ambient: None,
        diffuse: None,
        specular: None,
    },
};

/// `x^n` with `0^0 = 1` (`spec_pow`).
pub fn spec_pow(x: f64, n: f64) -> f64 {
    if n == 0.0 {
        return 1.0;
    }
    if x <= 0.0 {
        return 0.0;
    }
    x.powf(n)
}

/// Phong's lobe `max(0, r·v)^n_s`, r the mirror of l about n (l·n > 0).
pub fn phong_lobe(n: DVec3, l: DVec3, v: DVec3, shininess: f64) -> f64 {
    let r = 2.0 * l.dot(n) * n - l;
    spec_pow(r.dot(v).max(0.0), shininess)
}

/// Blinn-Phong's lobe `max(0, h·n)^n_s`, h = normalize(l + v) (l·n > 0).
pub fn blinn_phong_lobe(n: DVec3, l: DVec3, v: DVec3, shininess: f64) -> f64 {
    let sum = l + v;
    let len2 = sum.dot(sum);
    if len2 == 0.0 {
        return spec_pow(0.0, shininess);
    }
    spec_pow((sum / len2.sqrt()).dot(n).max(0.0), shininess)
}

/// The colour at a hit: the emission once, then per light, `k_a·I_a` once,
/// then per light sample (skipped where l·n ≤ 0 or the falloff is 0;
/// otherwise one shadow ray, counted in `shadow_rays`, unless the sample is
/// evaluated without visibility)
/// `falloff·(k_d·I_d·l·n + k_s·I_s·lobe)` if the sample is visible.
/// `pixel` and `pass` pick the light samples and the shadow rays' `Blend`
/// decisions. Where the hit has a surface, the Phong node's textures scale
/// `k_a`, `k_d` and `k_s`, the vertex colour's rgb `k_d`, and the object's
/// emission (times its texture) is added.
pub fn shade(
    world: &World,
    ray: &Ray,
    hit: &Hit,
    pixel: u32,
    pass: u32,
    shadow_rays: &mut u64,
) -> DVec3 {
    let mut node = resolve_shader(
        &world.shaders,
        hit.shader,
        hit.position,
        hit.geometric_normal,
    );
    let mut colour = DVec3::ZERO;
    let mut occlusion = 1.0;
    // (base colour, metallic, roughness) after the textures, in f64.
    let mut pbr_f64 = node.pbr.map(|m| {
        (
            m.base_colour.as_dvec3(),
            m.metallic as f64,
            m.roughness as f64,
        )
    });
    // (diffuse, specular, glossiness) after the textures, in f64.
    let mut sg_f64 = node.sg.map(|m| {
        (
            m.diffuse.as_dvec3(),
            m.specular.as_dvec3(),
            m.glossiness as f64,
        )
    });
    if let Some(s) = &hit.surface {
        let tex = |t: &Option<crate::scene::TextureRef>| {
            t.map_or(DVec3::ONE, |t| s.sample(world, &t).truncate())
        };
        node.ambient *= tex(&node.textures.ambient);
        node.diffuse *= tex(&node.textures.diffuse) * s.colour.truncate();
        node.specular *= tex(&node.textures.specular);
        // The metallic-roughness shader's `prepare`.
        if let Some(m) = &node.pbr {
            let c = m.base_colour.as_dvec3() * tex(&m.textures.base_colour) * s.colour.truncate();
            let mr = tex(&m.textures.metallic_roughness);
            pbr_f64 = Some((c, m.metallic as f64 * mr.z, m.roughness as f64 * mr.y));
        }
        // The specular-glossiness shader's `prepare`.
        if let Some(m) = &node.sg {
            let d = m.diffuse.as_dvec3() * tex(&m.textures.diffuse) * s.colour.truncate();
            let sg = m
                .textures
                .specular_glossiness
                .map_or(glam::DVec4::ONE, |t| s.sample(world, &t));
            let spec = m.specular.as_dvec3() * sg.truncate();
            sg_f64 = Some((d, spec, m.glossiness as f64 * sg.w));
        }
        let object = super::surface::object_of(world, hit.kind, hit.index) as usize;
        let maps = &world.objects[object].maps;
        let mut emission = maps.emission.as_dvec3() * tex(&maps.emission_texture);
        // KHR_materials_unlit: the vertex colour scales the colour emitted.
        if maps.emission_by_colour {
            emission *= s.colour.truncate();
        }
        colour += emission;
        // glTF's occlusionTexture: 1 + strength × (R − 1), for the
        // environment's light only (as shaders/stages/shade.wgsl).
        if let Some((t, strength)) = &maps.occlusion {
            occlusion = 1.0 + *strength as f64 * (s.sample(world, t).x - 1.0);
        }
    }
    let n = hit.shading_normal;
    let v = -ray.dir;
    let shadow_ray = AlphaRay::shadow(pixel, pass);
    for (i, light) in world.lights.iter().enumerate() {
        colour += node.ambient * light.ambient;
        let count = light.samples;
        let scale = match light.kind {
            super::lights::Kind::Environment { .. } => occlusion,
            _ => 1.0,
        };
        let start = colour;
        for j in 0..count {
            let uv = sample_2d(
                world.sampler,
                world.seed,
                pixel,
                1 + i as u32,
                pass.wrapping_mul(count).wrapping_add(j),
            );
            let mut ls = sample_light(light, hit.position, n, v, uv);
            if world.shadowed_environment
                && matches!(light.kind, super::lights::Kind::Environment { .. })
            {
                // Measurements only: the environment at infinity, traced.
                ls.distance = super::intersect::FAR;
            }
            let ln = ls.to_light.dot(n);
            // Light below the geometric surface: the surface blocks it, no
            // ray is cast (as on the GPU).
            if ln <= 0.0 || ls.falloff <= 0.0 || ls.to_light.dot(hit.geometric_normal) <= 0.0 {
                continue;
            }
            // Distance 0: evaluated without visibility (the environment),
            // no shadow ray to cast or count (as on the GPU).
            if ls.distance > 0.0 {
                *shadow_rays += 1;
                if occluded(world, hit, &ls, shadow_ray) {
                    continue;
                }
            }
            if let Some((c, metallic, roughness)) = pbr_f64 {
                let (d, sp) = metallic_roughness::brdf(n, ls.to_light, v, c, metallic, roughness);
                colour += ls.falloff * ln * (d * light.diffuse + sp * light.specular);
                continue;
            }
            if let Some((diffuse, specular, glossiness)) = sg_f64 {
                let (d, sp) =
                    specular_glossiness::brdf(n, ls.to_light, v, diffuse, specular, glossiness);
                colour += ls.falloff * ln * (d * light.diffuse + sp * light.specular);
                continue;
            }
            let lobe = if node.blinn {
                blinn_phong_lobe(n, ls.to_light, v, node.shininess)
            } else {
                phong_lobe(n, ls.to_light, v, node.shininess)
            };
            colour += ls.falloff
                * (node.diffuse * light.diffuse * ln + node.specular * light.specular * lobe);
        }
        if scale != 1.0 {
            colour = start + scale * (colour - start);
        }
    }
    colour
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spec_pow_zero_to_the_zero_is_one() {
        assert_eq!(spec_pow(0.0, 0.0), 1.0);
        assert_eq!(spec_pow(0.0, 2.0), 0.0);
        assert_eq!(spec_pow(-0.5, 3.0), 0.0);
        assert_eq!(spec_pow(0.5, 2.0), 0.25);
    }

    #[test]
    fn lobes_peak_at_the_mirror_direction() {
        let n = DVec3::Y;
        let l = DVec3::new(1.0, 1.0, 0.0).normalize();
        let v = DVec3::new(-1.0, 1.0, 0.0).normalize();
        assert!((phong_lobe(n, l, v, 20.0) - 1.0).abs() < 1e-12);
        assert!((blinn_phong_lobe(n, l, v, 20.0) - 1.0).abs() < 1e-12);
        assert_eq!(blinn_phong_lobe(n, l, -l, 3.0), 0.0);
    }

    #[test]
    fn checker_inset_picks_the_cell_behind_a_boundary_surface() {
        // The plane y = 0 seen from above (n = +Y) is looked up at y < 0.
        assert!(!checker_is_even(1.0, DVec3::new(0.5, 0.0, 0.5), DVec3::Y));
        assert!(checker_is_even(1.0, DVec3::new(0.5, 0.0, 0.5), -DVec3::Y));
        // Size 2: cells (1, 0, −1) sum to 0, cells (1, 0, 0) to 1.
        assert!(checker_is_even(2.0, DVec3::new(2.5, 1.0, -0.5), DVec3::Y));
        assert!(!checker_is_even(2.0, DVec3::new(2.5, 1.0, 0.5), DVec3::Y));
    }
}
