// `deltagi marker` (cli/marker_command.h).
#include "marker_command.h"

#include <string>

#include <fmt/core.h>

#include "deltagi/error.h"
#include "deltagi/image.h"
#include "live/marker_registration.h"
#include "messages.h"
#include "outputs.h"
#include "validators.h"

namespace fs = std::filesystem;

namespace deltagi::cli {

namespace {

constexpr double kPointsPerMetre = 72.0 / 0.0254;

// A one-page PDF of the cells (true for black), `cell` points wide, `margin` white cells around: the black
// cells as filled rectangles, the page the paper.
std::string markerPdf(const std::vector<bool>& cells, double cell, int margin) {
    const int side = kMarkerCells + 2 * margin;
    const double page = side * cell;
    std::string content = "0 g\n";
    for (int row = 0; row < kMarkerCells; ++row)
        for (int column = 0; column < kMarkerCells; ++column)
            if (cells[static_cast<size_t>(row) * kMarkerCells + column])
                // PDF's y goes up from the page's bottom; rows go down from the top.
                content += fmt::format("{:.4f} {:.4f} {:.4f} {:.4f} re f\n", (column + margin) * cell,
                                       page - (row + margin + 1) * cell, cell, cell);
    const std::vector<std::string> objects = {
        "<< /Type /Catalog /Pages 2 0 R >>",
        "<< /Type /Pages /Kids [3 0 R] /Count 1 >>",
        fmt::format("<< /Type /Page /Parent 2 0 R /MediaBox [0 0 {:.4f} {:.4f}] /Contents 4 0 R >>", page,
                    page),
        fmt::format("<< /Length {} >>\nstream\n{}endstream", content.size(), content),
    };
    std::string pdf = "%PDF-1.4\n";
    std::vector<size_t> offsets;
    for (size_t i = 0; i < objects.size(); ++i) {
        offsets.push_back(pdf.size());
        pdf += fmt::format("{} 0 obj\n{}\nendobj\n", i + 1, objects[i]);
    }
    const size_t xref = pdf.size();
    pdf += fmt::format("xref\n0 {}\n0000000000 65535 f \n", objects.size() + 1);
    for (size_t offset : offsets) pdf += fmt::format("{:010d} 00000 n \n", offset);
    pdf +=
        fmt::format("trailer\n<< /Size {} /Root 1 0 R >>\nstartxref\n{}\n%%EOF\n", objects.size() + 1, xref);
    return pdf;
}

}  // namespace

CLI::App* addMarkerCommand(CLI::App& app, MarkerArgs& args) {
    CLI::App* command = app.add_subcommand(
        "marker",
        "Write a printable AprilTag tag36h11 marker (PDF at its true size, or PNG) for \"markers\"");
    command->add_option("id", args.id, "The tag's id, 0-586")->required()->check(CLI::Range(0, 586));
    command->add_option("-o,--output", args.output, "marker.pdf (true size) or marker.png")->required();
    command->add_option("--size", args.size, "The black square's side in metres (default 0.12)")
        ->check(finiteRange(1e-3, 10.0));
    command->add_option("--margin", args.margin, "Cells of extra white paper around the tag (default 1)")
        ->check(CLI::Range(0, 20));
    command->add_option("--pixels-per-cell", args.pixelsPerCell, "PNG pixels per cell (default 32)")
        ->check(CLI::Range(1, 256));
    command->add_flag("-q,--quiet", args.quiet, "Print nothing but errors");
    return command;
}

int runMarker(const MarkerArgs& args) {
    const std::vector<bool> cells = markerCells(args.id);
    const std::string extension = args.output.extension().string();
    if (extension != ".pdf" && extension != ".png")
        throw InputError(args.output.string(), "expected a .pdf or .png file name");
    checkOutputs({args.output}, {});
    OutputFiles out;
    const int side = kMarkerCells + 2 * args.margin;
    if (extension == ".pdf") {
        out.bytes(markerPdf(cells, args.size / 8.0 * kPointsPerMetre, args.margin), args.output);
    } else {
        const int n = args.pixelsPerCell;
        Image image(side * n, side * n, 3, 1.0f);
        for (int y = 0; y < side * n; ++y)
            for (int x = 0; x < side * n; ++x) {
                const int row = y / n - args.margin, column = x / n - args.margin;
                if (row >= 0 && row < kMarkerCells && column >= 0 && column < kMarkerCells &&
                    cells[static_cast<size_t>(row) * kMarkerCells + column])
                    image.setRgb(x, y, glm::vec3(0.0f));
            }
        out.image(image, args.output);
    }
    out.commit();
    if (!args.quiet)
        note(
            "deltagi: wrote {}: tag36h11 id {}, its black square {:g} m wide ({:g} m with the paper's "
            "white)\n",
            args.output.string(), args.id, args.size, args.size / 8.0 * side);
    return 0;
}

}  // namespace deltagi::cli
