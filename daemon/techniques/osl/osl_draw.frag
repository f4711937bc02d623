in vec2 v_uv;
flat in vec4 v_chart;
flat in ivec4 v_tile;
layout(location = 0) out vec4 out_color;

uniform sampler2D u_atlas;
uniform vec2 u_atlas_size;

void main()
{
    // Clamp to the centres of the first and last texels inside the chart:
    // the bilinear footprint then never leaves the chart, which is the gutter.
    float size = float(v_tile.z);
    vec2 lo = (ceil(v_chart.xy * size - 0.5) + 0.5) / size;
    vec2 hi = (floor(v_chart.zw * size - 0.5) + 0.5) / size;
    vec2 uv = clamp(v_uv, lo, hi);
    vec2 atlas_uv = (vec2(v_tile.xy) + uv * size) / u_atlas_size;
    out_color = vec4(texture(u_atlas, atlas_uv).rgb, 1.0);
}
