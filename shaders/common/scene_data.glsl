// Scene data shared by every technique: instances and lights.
// Light positions are computed on the CPU per frame (daemon/scene.c) so that
// every technique lights a frame with bit-identical light positions.

struct Instance {
    vec4 pos_scale;   // world position, uniform scale
    vec4 albedo_mesh; // albedo, mesh index
};
layout(std430, binding = SB_SSBO_INSTANCES) readonly buffer InstanceBuffer { Instance instances[]; };

struct Light {
    vec4 color_radius; // colour, influence radius (attenuation is 0 beyond it)
};
layout(std430, binding = SB_SSBO_LIGHTS) readonly buffer LightBuffer { Light lights[]; };

// Rows of u_frame.counts.y positions; row 0 is the frame being drawn, OSL uses
// further rows for objects whose shading is from an earlier frame.
layout(std430, binding = SB_SSBO_LIGHT_POSITIONS) readonly buffer LightPositionBuffer { vec4 light_positions[]; };

