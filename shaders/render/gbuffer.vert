#version 450
// G-buffer: positions in LPS mm, normals in LPS (world) space.
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;

uniform mat4 view_projection;

out vec3 world_normal;

void main() {
    world_normal = normal;
    gl_Position = view_projection * vec4(position, 1.0);
}
