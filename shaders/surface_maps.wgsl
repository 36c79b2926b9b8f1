// What a material adds to every shader (scene::SurfaceMaps): a normal map,
// emission and alpha, per scene object (binding 22). Mirrored by
// render::layout::surface_maps, SURFACE_MAP_TEXELS texels an object:
//   0: emitted linear RGB, the emission texture use
//   1: the normal map's texture use, its scale, the alpha mode
//      (ALPHA_* below), the mask's cutoff
//   2: the opacity factor, the opacity texture use, 1 if single-sided, 0
//   3: the occlusion texture use, its strength, 1 if the emission is
//      scaled by the vertex colour (KHR_materials_unlit), 0
// (penumbra_NO_TEXTURE where a map is absent.)
//
// Every name starts with `penumbra_`: the shade stage compiles this file
// with users' shader files.

@group(0) @binding(22) var penumbra_surface_maps: texture_storage_2d<rgba32uint, read>;

const penumbra_SURFACE_MAP_TEXELS: u32 = 4u;
const penumbra_ALPHA_OPAQUE: u32 = 0u;
const penumbra_ALPHA_MASK: u32 = 1u;
const penumbra_ALPHA_BLEND: u32 = 2u;

fn penumbra_surface_map(object: u32, i: u32) -> vec4<u32> {
    let at = object * penumbra_SURFACE_MAP_TEXELS + i;
    return textureLoad(penumbra_surface_maps, vec2<u32>(at & 4095u, at >> 12u));
}
