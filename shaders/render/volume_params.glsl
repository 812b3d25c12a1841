// Volume ray casting's parameters (std140; volume.comp and the VOIT resolve
// with VOLUME). Binding 3: the resolve also reads OitParams at 1.
ISO_BLOCK_BEGIN(VolumeParams, 3)
ISO_MEMBER(mat4, inverse_view_projection) // clip -> LPS, with this frame's jitter: rays through the rasterized pixels
ISO_MEMBER(mat4, lps_to_index)            // LPS mm -> continuous voxel index
ISO_MEMBER(mat3, gradient_to_view)        // index-space gradient -> view space (world_to_view * transpose(lps_to_index))
ISO_MEMBER(vec4, eye)                     // LPS mm
ISO_MEMBER(vec4, forward)                 // unit view axis, LPS
ISO_MEMBER(vec4, dims_max)                // n - 1 per axis; w: chunk size (cells)
ISO_MEMBER(vec4, chunk_counts)            // chunks per axis
ISO_MEMBER(vec4, texel)                   // 1 / n per axis: index -> texture coordinate
ISO_MEMBER(vec4, tf_lut)                  // the tables: first point's value, texels per value, the last texel, last point's value
ISO_MEMBER(vec4, tf_low_end)              // (tau c, tau) below the first point
ISO_MEMBER(vec4, tf_high_end)             // and above the last
ISO_MEMBER(vec4, tf_top)                  // (E, P) at the last point
ISO_MEMBER(vec2, vol_near_far)                // the camera's planes (mm)
ISO_MEMBER(vec2, tf_clear)                // values at or below x, at or above y: opacity 0 (the lookup skipped)
ISO_MEMBER(vec2, value_map)               // value = texel * x + y (normalized integer textures)
ISO_MEMBER(ivec2, vol_image_size)
ISO_MEMBER(float, step_mm)                // the sample step
ISO_MEMBER(float, vol_epsilon)                // stop once the transmittance is below it
ISO_MEMBER(float, gradient_ref)           // gradient magnitude (value per mm) at which shading is full
ISO_MEMBER(float, sample_offset)          // where in its step a sample lies: 0.5 (midpoints); accumulated frames spread it
ISO_MEMBER(uint, mode)                    // 0 composite, 1 MIP, 2 MinIP
ISO_MEMBER(float, tf_width)               // value between the tables' texels (0: one point)
ISO_MEMBER(uint, clip_count)              // clip half-spaces
ISO_MEMBER(bool, skip_empty)              // skip chunks the transfer function leaves empty
ISO_BLOCK_END(VolumeParams)
