// The --camera FILE format (client/tools/camera_file.hpp): frames, comments,
// optional jitter, and errors that name the line and what was expected.
#include <gtest/gtest.h>

#include "camera_file.hpp"

namespace {

using dn::cli::CameraFileError;
using dn::cli::parse_camera_text;

const std::string kIdentity = "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1";

std::string error_of(const std::string& text) {
  try {
    parse_camera_text(text, "cams.txt");
  } catch (const CameraFileError& e) {
    return e.what();
  }
  return "";
}

TEST(CameraFile, ParsesFramesCommentsAndJitter) {
  const std::string text = "# exported by export_camera.py\n\n"
                           "frame 1 view " + kIdentity + " projection " + kIdentity + "\n"
                           "  frame 3 view 1 0 0 0 0 1 0 0 0 0 1 0 -2.5 0 1e-3 1 projection " + kIdentity +
                           " jitter 0.25 -0.25  # trailing comment\n";
  const auto cams = parse_camera_text(text);
  ASSERT_EQ(cams.size(), 2u);
  EXPECT_EQ(cams.at(1).view[0], 1.0f);
  EXPECT_FALSE(cams.at(1).jitter);
  EXPECT_EQ(cams.at(3).view[12], -2.5f);
  EXPECT_EQ(cams.at(3).view[14], 1e-3f);
  ASSERT_TRUE(cams.at(3).jitter);
  EXPECT_EQ((*cams.at(3).jitter)[1], -0.25f);
}

TEST(CameraFile, ErrorsNameTheLine) {
  const std::string ok = "frame 1 view " + kIdentity + " projection " + kIdentity + "\n";
  EXPECT_EQ(error_of("# c\n" + ok + "frame 2 view 1 0 0 projection " + kIdentity + "\n"),
            "cams.txt:3: expected 16 numbers after 'view' (column-major), found 3");
  EXPECT_EQ(error_of(ok + "camera 2\n"),
            "cams.txt:2: expected 'frame', found 'camera' (format: frame N view <16 floats> projection <16 floats> "
            "[jitter X Y])");
  EXPECT_EQ(error_of("frame 1 view " + kIdentity + "\n"),
            "cams.txt:1: expected 'projection', found the end of the line (format: frame N view <16 floats> "
            "projection <16 floats> [jitter X Y])");
  EXPECT_EQ(error_of("frame x view\n"), "cams.txt:1: expected a frame number (a finite number), found 'x'");
  EXPECT_EQ(error_of("frame 1.5 view\n"), "cams.txt:1: expected a frame number (an integer >= 0), found '1.5'");
  EXPECT_EQ(error_of("frame 1 view 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1q projection " + kIdentity + "\n"),
            "cams.txt:1: expected view[15] (a finite number), found '1q'");
  EXPECT_EQ(error_of(ok + ok), "cams.txt:2: frame 1 is given twice");
  EXPECT_EQ(error_of("frame 1 view " + kIdentity + " projection " + kIdentity + " jitter 0.5\n"),
            "cams.txt:1: expected jitter y (pixels), found the end of the line");
  EXPECT_EQ(error_of("frame 1 view " + kIdentity + " projection " + kIdentity + " extra\n"),
            "cams.txt:1: expected 'jitter', found 'extra' (format: frame N view <16 floats> projection <16 floats> "
            "[jitter X Y])");
  EXPECT_EQ(error_of("# nothing\n"), "cams.txt: no 'frame N view ... projection ...' lines");
  EXPECT_THROW(dn::cli::read_camera_file("/nonexistent/cams.txt"), CameraFileError);
}

}  // namespace
