// loom-inspector end to end under Xvfb: start it on a small graph for a few frames with
// --screenshot, check it exits 0 and that the screenshot shows the UI (node boxes, the texture
// viewer's image, text). Skips when xvfb-run or the inspector binary is missing.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>

#include "core/image/Image.h"
#include "tests/support/TestSupport.h"

namespace {

namespace fs = std::filesystem;

bool haveXvfbRun() {
    return std::system("command -v xvfb-run >/dev/null 2>&1") == 0;
}

// Pixels within `tol` (0..255 units) of an RGB colour.
size_t countColour(const loom::ImageData& img, int r, int g, int b, int tol = 6) {
    size_t n = 0;
    for (uint32_t y = 0; y < img.height; ++y)
        for (uint32_t x = 0; x < img.width; ++x) {
            int pr = int(img.at(x, y, 0) * 255.0f + 0.5f),
                pg = int(img.at(x, y, 1) * 255.0f + 0.5f),
                pb = int(img.at(x, y, 2) * 255.0f + 0.5f);
            if (std::abs(pr - r) <= tol && std::abs(pg - g) <= tol && std::abs(pb - b) <= tol) ++n;
        }
    return n;
}

TEST(InspectorScreenshot, RendersGraphUiUnderXvfb) {
#ifndef LOOM_INSPECTOR_BINARY
    GTEST_SKIP() << "loom-inspector was not built (libimgui-dev, libglfw3-dev missing)";
#else
    if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not installed (apt-get install xvfb)";
    loom::test::TempDir dir("loom-inspector-shot");
    std::string shot = dir / "shot.png";
    std::string src = LOOM_SOURCE_DIR;
    // timeout: a stuck X server or swapchain must fail the test, never hang it.
    std::string cmd = "cd '" + src +
                      "' && timeout -k 10 240 xvfb-run -a -s '-screen 0 1280x800x24' '" +
                      std::string(LOOM_INSPECTOR_BINARY) +
                      "' graphs/pt.json --scene scenes/cornell_box.json --width 64 --height 64"
                      " --frames 3 --view pt.color --screenshot '" +
                      shot + "' > '" + (dir / "log.txt") + "' 2>&1";
    int status = std::system(cmd.c_str());
    std::string log = loom::test::readFile(dir / "log.txt");
    ASSERT_TRUE(WIFEXITED(status)) << log;
    ASSERT_EQ(WEXITSTATUS(status), 0) << log;
    ASSERT_TRUE(fs::exists(shot)) << log;

    loom::ImageData img = loom::readImage(shot);
    EXPECT_EQ(img.width, 1280u);
    EXPECT_EQ(img.height, 800u);
    // Node boxes: the body colour of the graph view's nodes covers a real area (3 passes).
    size_t body = countColour(img, 48, 52, 62, 2);
    EXPECT_GT(body, 3u * 100u * 40u) << "node boxes missing";
    // Node headers (selected pass orange, others blue).
    EXPECT_GT(countColour(img, 214, 130, 40, 2) + countColour(img, 70, 96, 150, 2), 1000u);
    // Not a blank frame: many distinct colours (text, the rendered Cornell box, widgets).
    std::set<uint32_t> colours;
    for (size_t i = 0; i < img.pixels.size(); i += 4)
        colours.insert(uint32_t(img.pixels[i] * 255) << 16 |
                       uint32_t(img.pixels[i + 1] * 255) << 8 | uint32_t(img.pixels[i + 2] * 255));
    EXPECT_GT(colours.size(), 200u);
    // The texture viewer (lower left) shows the path tracer's image: red and green walls.
    size_t red = 0, green = 0;
    for (uint32_t y = img.height / 2; y < img.height; ++y)
        for (uint32_t x = 0; x < img.width / 2; ++x) {
            float r = img.at(x, y, 0), g = img.at(x, y, 1), b = img.at(x, y, 2);
            red += r > 0.2f && r > 1.5f * g && r > 1.5f * b;
            green += g > 0.2f && g > 1.5f * r && g > 1.5f * b;
        }
    EXPECT_GT(red, 1000u) << "texture viewer: no red wall";
    EXPECT_GT(green, 1000u) << "texture viewer: no green wall";
#endif
}

TEST(InspectorScreenshot, BadGraphExitsTwoWithMessage) {
#ifndef LOOM_INSPECTOR_BINARY
    GTEST_SKIP() << "loom-inspector was not built";
#else
    // Input errors are reported before any window opens: no display needed.
    loom::test::TempDir dir("loom-inspector-bad");
    loom::test::writeFile(dir / "bad.json",
                          "{\"passes\": [{\"name\": \"x\", \"type\": \"Nope\"}]}");
    std::string cmd = "timeout -k 5 60 '" + std::string(LOOM_INSPECTOR_BINARY) + "' '" +
                      (dir / "bad.json") + "' > '" + (dir / "log.txt") + "' 2>&1";
    int status = std::system(cmd.c_str());
    std::string log = loom::test::readFile(dir / "log.txt");
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 2) << log;
    EXPECT_NE(log.find("Nope"), std::string::npos) << log;
#endif
}

}  // namespace
