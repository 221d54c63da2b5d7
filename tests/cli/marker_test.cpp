// `deltagi marker`: the PDF prints the tag at its true size and the PNG holds it; both are found again by the
// detector that registers cameras.
#include <gtest/gtest.h>

#include <regex>
#include <sstream>

#include "live/marker_registration.h"
#include "test_cli.h"

namespace deltagi::test {
namespace {

class MarkerCommandTest : public CliTest {};

// The one marker `markers` holds, found in `image`?
bool detects(const Image& image, int id) {
    Marker m;
    m.id = id;
    m.size = 0.1f;
    const std::vector<Marker> markers = {m};
    return MarkerDetector(markers).detect(image).sightings.size() == 1;
}

TEST_F(MarkerCommandTest, WritesAPdfOfTheTrueSizeAndAPng) {
    const fs::path pdf = dir_ / "marker.pdf";
    CliResult r = run("marker 42 --size 0.12 -o " + quote(pdf.string()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::string text = readText(pdf);
    // 12 cells of 1.5 cm: 18 cm = 510.236 points.
    EXPECT_NE(text.find("/MediaBox [0 0 510.2362 510.2362]"), std::string::npos);
    // The cross-reference table points at each object.
    const size_t xref = text.find("\nxref\n");
    ASSERT_NE(xref, std::string::npos);
    std::istringstream table(text.substr(xref + 6));
    int first = 0, count = 0;
    table >> first >> count;
    std::string offset, generation, kind;
    table >> offset >> generation >> kind;  // the free entry
    for (int object = 1; object < count; ++object) {
        table >> offset >> generation >> kind;
        EXPECT_EQ(text.substr(std::stoul(offset), std::to_string(object).size() + 6),
                  std::to_string(object) + " 0 obj");
    }
    // Rasterized (2 points a pixel), the page holds tag 42.
    const int side = 256;
    Image page(side, side, 3, 1.0f);
    const std::regex rect(R"(([0-9.]+) ([0-9.]+) ([0-9.]+) ([0-9.]+) re f)");
    for (std::sregex_iterator it(text.begin(), text.end(), rect), end; it != end; ++it) {
        const double x = std::stod((*it)[1]), y = std::stod((*it)[2]), w = std::stod((*it)[3]),
                     h = std::stod((*it)[4]);
        for (int py = 0; py < side; ++py)
            for (int px = 0; px < side; ++px) {
                const double sx = (px + 0.5) * 2.0, sy = 510.2362 - (py + 0.5) * 2.0;
                if (sx >= x && sx < x + w && sy >= y && sy < y + h) page.setRgb(px, py, glm::vec3(0.0f));
            }
    }
    EXPECT_TRUE(detects(page, 42));
    EXPECT_FALSE(detects(page, 41));

    const fs::path png = dir_ / "marker.png";
    r = run("marker 42 -o " + quote(png.string()) + " --pixels-per-cell 8 --margin 2 -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const Image image = readImage(png);
    EXPECT_EQ(image.width(), 14 * 8);
    EXPECT_TRUE(detects(image, 42));

    r = run("marker 42 -o " + quote((dir_ / "marker.svg").string()));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.err.find("expected a .pdf or .png file name"), std::string::npos) << r.err;
    r = run("marker 587 -o " + quote(png.string()));
    EXPECT_EQ(r.exitCode, 2);
}

}  // namespace
}  // namespace deltagi::test
