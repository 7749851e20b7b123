// SPDX-License-Identifier: BSD-3-Clause
// The detector's gates that need no camera (cylfe::blob_passes), on hand-made blobs: area,
// fill, and the aspect range, which a blob cut by the frame's edge meets on the side the cut
// cannot have caused.
#include <gtest/gtest.h>

#include "cylfe/pipeline.hpp"

using namespace cylfe;

namespace {

// A blob of class 0 with box [x0, x1] x [y0, y1] (inclusive) and area px.
cyl_blob blob(uint16_t x0, uint16_t y0, uint16_t x1, uint16_t y1, uint32_t area, uint8_t flags = 0)
{
    cyl_blob b{};
    b.cls = 0;
    b.x0 = x0; b.y0 = y0; b.x1 = x1; b.y1 = y1;
    b.area = area;
    b.flags = flags;
    b.cx_px = 0.5 * (x0 + x1);
    b.cy_px = 0.5 * (y0 + y1);
    return b;
}

DetectorConfig gated()
{
    DetectorConfig c;
    c.gate[0].aspect_min = 0.25;   // width/height
    c.gate[0].aspect_max = 0.6;
    return c;
}

} // namespace

TEST(Gates, AspectAwayFromTheEdges)
{
    const DetectorConfig c = gated();
    EXPECT_TRUE(blob_passes(c, blob(100, 100, 119, 159, 1000), 640, 480));    // 20 x 60: 0.33
    EXPECT_FALSE(blob_passes(c, blob(100, 100, 109, 159, 500), 640, 480));    // 10 x 60: 0.17
    EXPECT_FALSE(blob_passes(c, blob(100, 100, 159, 159, 3000), 640, 480));   // 60 x 60: 1
    EXPECT_TRUE(blob_passes(c, blob(100, 100, 114, 159, 800), 640, 480));     // 15 x 60: exactly 0.25
}

TEST(Gates, WidthCutByLeftOrRightEdgeMeetsTheUpperLimitOnly)
{
    const DetectorConfig c = gated();
    // a wide strip on the floor at the left edge: already too wide, cut or not
    EXPECT_FALSE(blob_passes(c, blob(0, 244, 134, 278, 3000, CYL_BLOB_TOUCH_LEFT), 640, 480));
    EXPECT_FALSE(blob_passes(c, blob(505, 244, 639, 278, 3000, CYL_BLOB_TOUCH_RIGHT), 640, 480));
    // a sliver of a landmark at the right edge: too narrow as seen, but it may be cut
    EXPECT_TRUE(blob_passes(c, blob(635, 155, 639, 200, 200, CYL_BLOB_TOUCH_RIGHT), 640, 480));
}

TEST(Gates, HeightCutByTopOrBottomEdgeMeetsTheLowerLimitOnly)
{
    const DetectorConfig c = gated();
    // a landmark cut at the bottom looks too wide: kept
    EXPECT_TRUE(blob_passes(c, blob(300, 440, 329, 479, 1000, CYL_BLOB_TOUCH_BOTTOM), 640, 480));
    // a thin pole leaving the top of the frame is too narrow however tall it is: dropped
    EXPECT_FALSE(blob_passes(c, blob(300, 0, 304, 200, 900, CYL_BLOB_TOUCH_TOP), 640, 480));
}

TEST(Gates, CutBothWaysMeetsNeither)
{
    const DetectorConfig c = gated();
    EXPECT_TRUE(blob_passes(c, blob(0, 0, 4, 200, 900, CYL_BLOB_TOUCH_LEFT | CYL_BLOB_TOUCH_TOP), 640, 480));
    EXPECT_TRUE(blob_passes(c, blob(0, 0, 200, 4, 900, CYL_BLOB_TOUCH_LEFT | CYL_BLOB_TOUCH_TOP), 640, 480));
}

TEST(Gates, AreaAndFill)
{
    DetectorConfig c;
    c.gate[0].max_area_px = 1000;
    c.gate[0].min_fill = 0.3;
    EXPECT_TRUE(blob_passes(c, blob(0, 0, 9, 9, 100), 640, 480));
    EXPECT_FALSE(blob_passes(c, blob(0, 0, 99, 99, 1001), 640, 480));    // larger than the limit
    EXPECT_FALSE(blob_passes(c, blob(0, 0, 9, 9, 29), 640, 480));        // fills 0.29 of its box
    EXPECT_TRUE(blob_passes(c, blob(0, 0, 9, 9, 30), 640, 480));
}
