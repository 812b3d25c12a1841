// The C++ side of the passes' uniform blocks. Each pass's parameters are
// written once, in shaders/<dir>/<pass>_params.glsl (ISO_BLOCK_BEGIN /
// ISO_MEMBER / ISO_BLOCK_END); shaders/std140.glsl turns that file into a
// std140 uniform block and this header into a C++ struct with the same
// offsets (each member aligned as std140 aligns it; mat3 is three vec4
// columns), plus a table of member offsets that
// tests/gl/uniform_blocks_test.cpp compares with the linked programs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace iso::passes::std140 {

struct Member {
    const char* name;
    std::size_t offset, size;
};

// A mat3 as std140 stores it: three columns, each padded to a vec4.
inline glm::mat3x4 mat3(const glm::mat3& m) {
    return glm::mat3x4(glm::vec4(m[0], 0.0f), glm::vec4(m[1], 0.0f), glm::vec4(m[2], 0.0f));
}

} // namespace iso::passes::std140

// GLSL type -> C++ type and std140 base alignment.
#define ISO_STD140_TYPE_float float
#define ISO_STD140_TYPE_int std::int32_t
#define ISO_STD140_TYPE_uint std::uint32_t
#define ISO_STD140_TYPE_bool std::uint32_t
#define ISO_STD140_TYPE_vec2 glm::vec2
#define ISO_STD140_TYPE_ivec2 glm::ivec2
#define ISO_STD140_TYPE_vec4 glm::vec4
#define ISO_STD140_TYPE_mat3 glm::mat3x4
#define ISO_STD140_TYPE_mat4 glm::mat4
#define ISO_STD140_ALIGN_float 4
#define ISO_STD140_ALIGN_int 4
#define ISO_STD140_ALIGN_uint 4
#define ISO_STD140_ALIGN_bool 4
#define ISO_STD140_ALIGN_vec2 8
#define ISO_STD140_ALIGN_ivec2 8
#define ISO_STD140_ALIGN_vec4 16
#define ISO_STD140_ALIGN_mat3 16
#define ISO_STD140_ALIGN_mat4 16

namespace iso::passes {

// The structs.
#define ISO_BLOCK_BEGIN(block, binding_point)                                                                          \
    struct alignas(16) block {                                                                                         \
        static constexpr unsigned binding = binding_point;                                                             \
        static constexpr const char* name = #block;
#define ISO_MEMBER(type, member) alignas(ISO_STD140_ALIGN_##type) ISO_STD140_TYPE_##type member{};
#define ISO_BLOCK_END(block)                                                                                           \
    }                                                                                                                  \
    ;
#include "shaders/render/gbuffer_params.glsl"
#include "shaders/render/lighting_params.glsl"
#include "shaders/render/overlay_params.glsl"
#include "shaders/ao/zrange_params.glsl"
#include "shaders/ao/voxelize_params.glsl"
#include "shaders/ao/cone_params.glsl"
#include "shaders/ao/upsample_params.glsl"
#include "shaders/ao/disk_params.glsl"
#include "shaders/render/oit_params.glsl"
#include "shaders/render/volume_params.glsl"
#undef ISO_BLOCK_BEGIN
#undef ISO_MEMBER
#undef ISO_BLOCK_END

// Their members' offsets, for the tests: members(static_cast<const B*>(nullptr)).
#define ISO_BLOCK_BEGIN(block, binding_point)                                                                          \
    inline std::vector<std140::Member> members(const block*) {                                                         \
        using B = block;                                                                                               \
        return {
#define ISO_MEMBER(type, member) {#member, offsetof(B, member), sizeof(B::member)},
#define ISO_BLOCK_END(block)                                                                                           \
    }                                                                                                                  \
    ;                                                                                                                  \
    }
#include "shaders/render/gbuffer_params.glsl"
#include "shaders/render/lighting_params.glsl"
#include "shaders/render/overlay_params.glsl"
#include "shaders/ao/zrange_params.glsl"
#include "shaders/ao/voxelize_params.glsl"
#include "shaders/ao/cone_params.glsl"
#include "shaders/ao/upsample_params.glsl"
#include "shaders/ao/disk_params.glsl"
#include "shaders/render/oit_params.glsl"
#include "shaders/render/volume_params.glsl"
#undef ISO_BLOCK_BEGIN
#undef ISO_MEMBER
#undef ISO_BLOCK_END

} // namespace iso::passes
