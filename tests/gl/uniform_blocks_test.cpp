// Every pass's parameter block as C++ uploads it (renderer/passes/std140.hpp)
// and as the linked program reads it: same binding, every member at the same
// byte offset, and the block's size within the struct's. Exact: a member
// added on one side only, or a type whose std140 alignment differs, fails.
#include "renderer/passes/std140.hpp"

#include "renderer/gl/context.hpp"
#include "renderer/gl/objects.hpp"
#include "renderer/passes/gbuffer_layout.hpp"
#include "gl_test.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using UniformBlocks = test::GlTest;
using namespace iso::passes;

namespace {

template <class P> void expect_block_matches(const gl::Program& prog, const std::string& program_name) {
    SCOPED_TRACE(program_name + ": " + P::name);
    const GLuint block = glGetProgramResourceIndex(prog.id(), GL_UNIFORM_BLOCK, P::name);
    ASSERT_NE(block, GLuint(GL_INVALID_INDEX)) << "the program has no block " << P::name;
    const GLenum block_props[] = {GL_BUFFER_BINDING, GL_BUFFER_DATA_SIZE};
    GLint bv[2] = {-1, -1};
    glGetProgramResourceiv(prog.id(), GL_UNIFORM_BLOCK, block, 2, block_props, 2, nullptr, bv);
    EXPECT_EQ(GLuint(bv[0]), P::binding);
    EXPECT_LE(std::size_t(bv[1]), sizeof(P));
    const auto members = passes::members(static_cast<const P*>(nullptr));
    ASSERT_FALSE(members.empty());
    EXPECT_GE(std::size_t(bv[1]), members.back().offset + 4) << "the last member fits";
    GLint active = 0;
    const GLenum count_prop = GL_NUM_ACTIVE_VARIABLES;
    glGetProgramResourceiv(prog.id(), GL_UNIFORM_BLOCK, block, 1, &count_prop, 1, nullptr, &active);
    EXPECT_EQ(std::size_t(active), members.size()) << "members on one side only";
    for (const auto& m : members) {
        const GLuint u = glGetProgramResourceIndex(prog.id(), GL_UNIFORM, m.name);
        ASSERT_NE(u, GLuint(GL_INVALID_INDEX)) << m.name;
        const GLenum props[] = {GL_OFFSET, GL_BLOCK_INDEX};
        GLint v[2] = {-1, -1};
        glGetProgramResourceiv(prog.id(), GL_UNIFORM, u, 2, props, 2, nullptr, v);
        EXPECT_EQ(std::size_t(v[0]), m.offset) << m.name;
        EXPECT_EQ(GLuint(v[1]), block) << m.name;
    }
}

} // namespace

TEST_F(UniformBlocks, CppStructsMatchTheLinkedPrograms) {
    expect_block_matches<GBufferParams>(
        gl::Program::from_files({"render/gbuffer.vert", "render/gbuffer.frag"}, gbuffer_defines()), "gbuffer");
    expect_block_matches<LightingParams>(gl::Program::from_files({"render/fullscreen.vert", "render/lighting.frag"}),
                                         "lighting");
    expect_block_matches<OverlayParams>(gl::Program::from_files({"render/overlay.vert", "render/overlay.frag"}),
                                        "overlay");
    expect_block_matches<ZRangeParams>(gl::Program::from_files({"ao/zrange.comp"}), "zrange");
    expect_block_matches<UpsampleParams>(gl::Program::from_files({"ao/ao_upsample.comp"}), "ao_upsample");
    for (const char* disk :
         {"ao/disk_gather.comp", "ao/disk_element.comp", "ao/disk_parent.comp", "ao/disk_blend.comp"})
        expect_block_matches<DiskParams>(gl::Program::from_files({disk}), disk);
    for (int layers : {1, 8}) {
        const std::string d = "#define LAYERS " + std::to_string(layers) + "\n";
        expect_block_matches<VoxelizeParams>(gl::Program::from_files({"ao/slicemap.vert", "ao/slicemap.frag"}, d),
                                             "voxelize " + d);
        expect_block_matches<ConeParams>(gl::Program::from_files({"ao/cone.comp"}, d), "cone " + d);
        expect_block_matches<ConeParams>(gl::Program::from_files({"ao/cone.comp"}, d + "#define COARSE 1\n"),
                                         "cone coarse " + d);
    }
    // The volume's march: its own pass and the VOIT resolve that marches it between fragments.
    expect_block_matches<VolumeParams>(gl::Program::from_files({"render/volume.comp"}), "volume");
    expect_block_matches<VolumeParams>(gl::Program::from_files({"render/oit_resolve.comp"}, "#define VOLUME 1\n"),
                                       "oit_resolve with the volume");
    expect_block_matches<OitParams>(gl::Program::from_files({"render/oit_resolve.comp"}, "#define VOLUME 1\n"),
                                    "oit_resolve with the volume");
}

TEST_F(UniformBlocks, Std140LayoutOfTheCppStructs) {
    // Hand-computed std140 offsets of the block with every member type.
    EXPECT_EQ(offsetof(ConeParams, world_to_view), 0u);
    EXPECT_EQ(offsetof(ConeParams, proj_scale), 48u) << "mat3: three vec4 columns";
    EXPECT_EQ(offsetof(ConeParams, sm_proj_scale), 56u);
    EXPECT_EQ(offsetof(ConeParams, size), 64u);
    EXPECT_EQ(offsetof(ConeParams, near_plane), 88u);
    EXPECT_EQ(offsetof(LightingParams, background), 48u);
    EXPECT_EQ(offsetof(LightingParams, use_ao), 64u) << "bool: 4 bytes";
    EXPECT_EQ(offsetof(VoxelizeParams, scene_far), 128u);
    const glm::mat3x4 m = std140::mat3(glm::mat3(1, 2, 3, 4, 5, 6, 7, 8, 9));
    EXPECT_EQ(m[1], glm::vec4(4, 5, 6, 0));
}
