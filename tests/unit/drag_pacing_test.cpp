// How the 3D view's drag frames keep pace (renderer/core/drag_pacing.hpp):
// slow frames go to half size, then to coarser levels of detail by the
// square root of what is left; fast ones come back a step at a time; frames
// asked for before a change do not count twice; a drag over a view whose
// still frames are slow starts coarse.
#include <gtest/gtest.h>

#include "renderer/core/drag_pacing.hpp"

using iso::core::DragPacing;

TEST(DragPacing, SlowFramesGoToHalfSizeThenToCoarserDetail) {
    DragPacing p;
    EXPECT_EQ(p.scale(), 1.0);
    EXPECT_EQ(p.coarsen(), 1.0);
    p.frame(1, 60.0, false, 1); // within the aim: nothing changes
    EXPECT_EQ(p.scale(), 1.0);
    p.frame(2, 200.0, false, 5); // 2.9x: half size (3x) is enough
    EXPECT_EQ(p.scale(), 0.5);
    EXPECT_EQ(p.coarsen(), 1.0);
    p.frame(4, 900.0, false, 6); // asked for before the change: ignored
    EXPECT_EQ(p.coarsen(), 1.0);
    p.frame(6, 300.0, true, 9); // 4.3x at half size: 2^round(log2(4.3) / 2) = 2
    EXPECT_EQ(p.coarsen(), 2.0);
    p.frame(10, 100.0, true, 12); // 1.4x: under 1.5, kept
    EXPECT_EQ(p.coarsen(), 2.0);
    p.frame(13, 2000.0, true, 14); // up to kMaxCoarsen at most
    EXPECT_EQ(p.coarsen(), DragPacing::kMaxCoarsen);
    p.frame(15, 5000.0, true, 16);
    EXPECT_EQ(p.coarsen(), DragPacing::kMaxCoarsen);
    EXPECT_EQ(p.scale(), 0.5);
}

TEST(DragPacing, FastFramesComeBackAStepAtATime) {
    DragPacing p;
    p.frame(1, 2000.0, false, 1); // 28.6x: half size (3x) leaves 9.5x: 2^round(log2(9.5) / 2) = 4
    EXPECT_EQ(p.scale(), 0.5);
    EXPECT_EQ(p.coarsen(), 4.0);
    p.frame(2, 10.0, true, 2);
    EXPECT_EQ(p.coarsen(), 2.0);
    p.frame(2, 10.0, true, 2); // the same request again: asked for before the change
    EXPECT_EQ(p.coarsen(), 2.0);
    p.frame(3, 10.0, true, 3);
    EXPECT_EQ(p.coarsen(), 1.0);
    EXPECT_EQ(p.scale(), 0.5);
    p.frame(4, 10.0, true, 4);
    EXPECT_EQ(p.scale(), 1.0);
    p.frame(5, 10.0, false, 5); // fast at full size: stays
    EXPECT_EQ(p.scale(), 1.0);
    EXPECT_EQ(p.coarsen(), 1.0);
}

TEST(DragPacing, ADragOverSlowStillFramesStartsCoarse) {
    DragPacing quick;
    quick.start(300.0, 1); // still frames under 400 ms: the drag starts at full size and detail
    EXPECT_EQ(quick.scale(), 1.0);
    EXPECT_EQ(quick.coarsen(), 1.0);
    DragPacing slow;
    slow.start(560.0, 7); // 8x: half size, then 2.7x -> x2
    EXPECT_EQ(slow.scale(), 0.5);
    EXPECT_EQ(slow.coarsen(), 2.0);
    slow.frame(7, 900.0, false, 8); // a frame asked for before the drag started: ignored
    EXPECT_EQ(slow.coarsen(), 2.0);
    slow.start(5000.0, 9); // already paced: a new drag keeps what the last one learnt
    EXPECT_EQ(slow.coarsen(), 2.0);
}
