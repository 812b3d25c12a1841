#version 450
// Writes the world normal, the object id and the albedo; depth goes to the
// (reversed-Z, float) depth attachment.
in vec3 world_normal;

uniform uint object_id;
uniform vec3 albedo;

layout(location = 0) out vec4 out_normal;   // RGBA16F: world normal, w = 1 on geometry
layout(location = 1) out uint out_id;       // R32UI
layout(location = 2) out vec4 out_albedo;   // RGBA8

void main() {
    vec3 n = normalize(world_normal);
    // Two-sided: open surfaces (cut by the volume border) show their inside.
    if (!gl_FrontFacing) n = -n;
    out_normal = vec4(n, 1.0);
    out_id = object_id;
    out_albedo = vec4(albedo, 1.0);
}
