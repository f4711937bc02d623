// Scene data shared by every technique: instances and lights.
// Light positions are computed on the CPU per frame (daemon/scene.c) so that
// every technique lights a frame with bit-identical light positions.

struct Instance {
    vec4 pos_scale;   // world position, uniform scale
    vec4 albedo_mesh; // albedo, mesh index
};
layout(std430, binding = 0) readonly buffer InstanceBuffer { Instance instances[]; };

struct Light {
    vec4 color_radius; // colour, influence radius (attenuation is 0 beyond it)
};
layout(std430, binding = 1) readonly buffer LightBuffer { Light lights[]; };

// Rows of u_light_count positions; row 0 is the frame being drawn, OSL uses
// further rows for objects whose shading is from an earlier frame.
layout(std430, binding = 2) readonly buffer LightPositionBuffer { vec4 light_positions[]; };

uniform int u_light_count;
uniform vec3 u_eye;
