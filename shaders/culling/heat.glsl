// The light-count heat map: light evaluations per pixel this frame, written
// only on the frames the harness captures (u_heat_on), so that uncaptured
// frames pay nothing for it. daemon/techniques/shared/heat.c owns the image.
layout(binding = SB_IMG_HEAT, r32ui) uniform coherent uimage2D u_heat;
uniform int u_heat_on;

void heat_add(ivec2 pixel, uint evaluations)
{
    if (u_heat_on != 0)
        imageAtomicAdd(u_heat, pixel, evaluations);
}

void heat_set(ivec2 pixel, uint evaluations)
{
    if (u_heat_on != 0)
        imageStore(u_heat, pixel, uvec4(evaluations));
}
