// Scene data shared by every technique: instances, materials and lights.
// Light positions are computed on the CPU per frame (daemon/scene/scene.c) so
// that every technique lights a frame with bit-identical light positions.

// std430, 48 bytes; written by daemon/gpu/gpu_scene.c in this order.
struct Instance {
    vec4 pos_scale;   // world position, uniform scale
    vec4 albedo_mesh; // albedo, mesh index (0 sphere, 1 cube, 2 plane)
    vec4 material;    // specular, shininess, metallic, roughness
};
layout(std430, binding = SB_SSBO_INSTANCES) readonly buffer InstanceBuffer { Instance instances[]; };

// One object's material. Phong reads albedo, specular and shininess;
// metallic and roughness are there for the physically based models.
struct Material {
    vec3 albedo;
    float specular;
    float shininess;
    float metallic;
    float roughness;
};

Material instance_material(int id)
{
    Instance inst = instances[id];
    return Material(inst.albedo_mesh.rgb, inst.material.x, inst.material.y, inst.material.z,
                    inst.material.w);
}

// std430, 64 bytes; written by daemon/gpu/gpu_scene.c in this order. The
// type is a float holding LIGHT_POINT, LIGHT_SPOT or LIGHT_DIRECTIONAL
// (enum scene_light_type); a point light's other fields are 0.
struct Light {
    vec4 color_radius;   // colour (scaled by scene.light_intensity), influence radius
                         // (attenuation is 0 beyond it; unused by directional lights)
    vec4 direction_type; // unit direction the light shines (spot, directional), type
    vec4 cone;           // spot: cos outer, cos inner, 1 / max(cos inner - cos outer,
                         // 1e-3) (glTF's angle scale), sin outer (for the culling)
    vec4 falloff;        // x: LIGHT_FALLOFF_WINDOW or LIGHT_FALLOFF_GLTF (enum
                         // scene_light_falloff), y: glTF range (0: none)
};
const int LIGHT_FALLOFF_WINDOW = 0, LIGHT_FALLOFF_GLTF = 1;
const int LIGHT_POINT = 0, LIGHT_SPOT = 1, LIGHT_DIRECTIONAL = 2;
layout(std430, binding = SB_SSBO_LIGHTS) readonly buffer LightBuffer { Light lights[]; };

// Rows of u_frame.counts.y positions; row 0 is the frame being drawn, OSL uses
// further rows for objects whose shading is from an earlier frame.
layout(std430, binding = SB_SSBO_LIGHT_POSITIONS) readonly buffer LightPositionBuffer { vec4 light_positions[]; };

