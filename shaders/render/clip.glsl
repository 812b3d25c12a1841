// The frame's clip (FrameLook::clip: a crop box and planes, LPS mm) cuts the
// surfaces' fragments as volume_march.glsl cuts the volume's rays: a
// fragment outside any half-space (dot(normal, p) < offset) is discarded.
#ifdef CLIP
uniform vec4 clip_planes[16];   // normal, offset
uniform int clip_count;
in vec3 world_position;
void clip_fragment() {
    for (int i = 0; i < clip_count; ++i)
        if (dot(clip_planes[i].xyz, world_position) < clip_planes[i].w) discard;
}
#else
void clip_fragment() {}
#endif
