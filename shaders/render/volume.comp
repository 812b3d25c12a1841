#version 450
#extension GL_GOOGLE_include_directive : require
// Volume ray casting over the lit opaque image when no translucent surface
// is drawn (with translucent surfaces the VOIT resolve marches the volume
// between its fragments: oit_resolve.comp with VOLUME). Per pixel: the
// volume from the near plane (or where the clipped box begins) to the
// opaque depth, then what is behind it at the remaining transmittance.
#include "std140.glsl"
#include "volume_params.glsl"
#include "shading.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 1, rgba8) uniform image2D color;   // opaque result in, composite out (sRGB-encoded RGBA8)

vec3 acc = vec3(0.0);
float transmittance = 1.0;

#include "volume_march.glsl"

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= vol_image_size.x || p.y >= vol_image_size.y) return;
    if (!volume_begin(p)) return;
    volume_until(vol_t1);
    volume_end();
    vec4 under = imageLoad(color, p);
    vec3 result = acc + transmittance * srgb_to_linear(under.rgb);
    imageStore(color, p, vec4(srgb(result), 1.0 - transmittance * (1.0 - under.a)));
}
