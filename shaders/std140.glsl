// Uniform blocks shared with C++. A pass's parameters are written once, in
// shaders/<dir>/<pass>_params.glsl, as ISO_BLOCK_BEGIN / ISO_MEMBER /
// ISO_BLOCK_END; here they become a std140 uniform block, and
// renderer/passes/std140.hpp turns the same file into the C++ struct the
// pass uploads (tests/gl/uniform_blocks_test.cpp checks every offset).
#define ISO_BLOCK_BEGIN(block, binding_point) layout(std140, binding = binding_point) uniform block {
#define ISO_MEMBER(type, member) type member;
#define ISO_BLOCK_END(block) };
