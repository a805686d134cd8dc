// dn denoise's frame range from the files a pattern names, and the check that
// every file of a run exists (client/tools/frame_range.hpp).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "args.hpp"
#include "frame_range.hpp"
#include "frame_source.hpp"

namespace {

namespace fs = std::filesystem;
using namespace dn::cli;

class FrameRangeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("dn_frame_range_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  void touch(const std::string& name) { std::ofstream(dir / name) << "x"; }
  std::string pattern(const std::string& p) { return (dir / p).string(); }
  fs::path dir;
};

TEST_F(FrameRangeTest, FindsTheFramesThePatternSpells) {
  for (const char* n : {"f_0003.exr", "f_0004.exr", "f_0007.exr", "f_004.exr", "f_00005.exr", "f_0006.png", "g_0001.exr"})
    touch(n);
  EXPECT_EQ(existing_frames(pattern("f_%04d.exr")), (std::vector<long long>{3, 4, 7}));
  EXPECT_EQ(existing_frames(pattern("f_####.exr")), (std::vector<long long>{3, 4, 7}));
  // %d: unpadded numbers only, so "0003" is not frame 3.
  touch("h_12.exr");
  touch("h_012.exr");
  EXPECT_EQ(existing_frames(pattern("h_%d.exr")), (std::vector<long long>{12}));
  EXPECT_TRUE(existing_frames(pattern("none/f_%04d.exr")).empty());
}

TEST_F(FrameRangeTest, DetectsTheRunFromTheLowestFrame) {
  for (const char* n : {"f_0003.exr", "f_0004.exr", "f_0005.exr", "f_0007.exr", "f_0008.exr"}) touch(n);
  const FrameRange r = resolve_frame_range(pattern("f_%04d.exr"), std::nullopt, std::nullopt, 1);
  EXPECT_EQ(r.start, 3);
  EXPECT_EQ(r.end, 5);
  EXPECT_NE(r.detected.find("frames 3..5 (3 files) found from"), std::string::npos) << r.detected;
  EXPECT_NE(r.detected.find("frame 6 is missing, so the 2 later files are left out"), std::string::npos)
      << r.detected;
  // One bound given: the other is detected.
  EXPECT_EQ(resolve_frame_range(pattern("f_%04d.exr"), 7, std::nullopt, 1).end, 8);
  EXPECT_EQ(resolve_frame_range(pattern("f_%04d.exr"), std::nullopt, 8, 1).start, 3);
  // Both given: taken as they are, nothing looked up.
  const FrameRange given = resolve_frame_range(pattern("f_%04d.exr"), 10, 20, 1);
  EXPECT_EQ(given.start, 10);
  EXPECT_EQ(given.end, 20);
  EXPECT_TRUE(given.detected.empty());
  // --step 2 from 3: 3, 5, then 7 exists too.
  EXPECT_EQ(resolve_frame_range(pattern("f_%04d.exr"), std::nullopt, std::nullopt, 2).end, 7);
}

TEST_F(FrameRangeTest, NoMatchingFileOrAPlaceholderInADirectoryIsAnError) {
  EXPECT_THROW(resolve_frame_range(pattern("f_%04d.exr"), std::nullopt, std::nullopt, 1), std::runtime_error);
  EXPECT_THROW(resolve_frame_range(pattern("%04d/f.exr"), std::nullopt, std::nullopt, 1), UsageError);
}

TEST_F(FrameRangeTest, RequireFrameFilesNamesTheFirstMissing) {
  touch("f_0001.exr");
  touch("f_0003.exr");
  EXPECT_NO_THROW(require_frame_files({1, 3}, pattern("f_%04d.exr"), "--input"));
  try {
    require_frame_files({1, 2, 3, 4}, pattern("f_%04d.exr"), "--input");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "--input: " + pattern("f_0002.exr") +
                                         " (frame 2) does not exist (and 1 more of the 4 frames are missing)");
  }
}

TEST(FramePattern, SplitsAtThePlaceholder) {
  const auto p = split_frame_pattern("out/100%%_%04d.exr");
  ASSERT_TRUE(p);
  EXPECT_EQ(p->prefix, "out/100%_");
  EXPECT_EQ(p->suffix, ".exr");
  EXPECT_EQ(p->width, 4);
  EXPECT_EQ(format_frame_path("out/100%%_%04d.exr", 7), "out/100%_0007.exr");
  EXPECT_EQ(format_frame_path("a_##.exr", 123), "a_123.exr");
  EXPECT_FALSE(split_frame_pattern("still.exr"));
}

}  // namespace
