// `pintag render`: one tag as PNG (raster, dpi recorded) or SVG (vector, exact size).

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "commands/commands.hpp"
#include "commands/option_checks.hpp"
#include "pintag/codec/file_output.hpp"
#include "pintag/codec/png_io.hpp"
#include "pintag/codec/tag_raster.hpp"
#include "pintag/codec/tag_svg.hpp"

namespace pintag::cli {
namespace {

constexpr int kMaxSquarePx = 16384;
constexpr double kMaxSquareMm = 1000;

struct RenderArgs {
  int key = -1;
  std::optional<int> size_px;
  std::optional<double> size_mm;
  double dpi = 300;
  bool dpi_given = false;  ///< --dpi was given (PINTAG has no variable for it): SVGs take none
  std::string output;
};

/// As the user would write it: 0.5, 50, 300 (not std::to_string's 0.500000).
std::string Shortest(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

std::string Extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

void Run(const RenderArgs& args) {
  const std::string ext = Extension(args.output);
  if (ext != ".png" && ext != ".svg") {
    throw UsageError("output must end in .png or .svg, got '" + args.output + "'");
  }
  if (args.size_px.has_value() == args.size_mm.has_value()) {
    throw UsageError("give exactly one of --size-px and --size-mm");
  }
  // Before the tag is drawn (seconds, and gigabytes, for the largest): a mistyped directory.
  CheckFileToWrite("-o", args.output);
  const TagKey key(static_cast<std::uint16_t>(args.key));

  if (ext == ".svg") {
    // An SVG is sized in millimetres or pixels and has no resolution: a --dpi given for it was
    // dropped without a word.
    if (args.dpi_given) {
      throw UsageError("--dpi is for PNGs; an SVG is sized by --size-mm or --size-px alone");
    }
    const TagSvgOptions options = args.size_mm ? TagSvgOptions{*args.size_mm, "mm"}
                                               : TagSvgOptions{double(*args.size_px), "px"};
    // Written whole: the stream's flush was checked, its close not (WriteWholeFile).
    if (const std::string failure = WriteWholeFile(args.output, RenderTagSvg(key, options));
        !failure.empty()) {
      throw std::runtime_error("cannot write " + args.output + ": " + failure);
    }
  } else {
    const int square_px = args.size_px
                              ? *args.size_px
                              : static_cast<int>(std::lround(*args.size_mm / 25.4 * args.dpi));
    if (square_px < kMinTagSquarePx || square_px > kMaxSquarePx) {
      throw UsageError("--size-mm " + Shortest(*args.size_mm) + " at " + Shortest(args.dpi) +
                       " dpi gives a " + std::to_string(square_px) + " px square; it must be " +
                       std::to_string(kMinTagSquarePx) + " to " + std::to_string(kMaxSquarePx) +
                       " px");
    }
    const TagRaster raster = RenderTagRaster(key, {square_px, 4});
    std::string error;
    if (!WritePng(raster.image, args.output, args.dpi, &error)) throw std::runtime_error(error);
  }
  std::cout << "wrote key " << args.key << " to " << args.output << "\n";
}

void AddRenderCommand(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand("render", "Render one tag as PNG or SVG");
  cmd->add_option("--key", args->key, "tag key, 0-32767")->required()->transform(TagKeyText());
  cmd->add_option("--size-px", args->size_px, "black square side in pixels (quiet zone added)")
      ->check(CLI::Range(kMinTagSquarePx, kMaxSquarePx));
  cmd->add_option("--size-mm", args->size_mm, "black square side in millimetres (quiet zone added)")
      ->check(FiniteNumber())
      ->check(CLI::Range(1.0, kMaxSquareMm));
  CLI::Option* dpi =
      cmd->add_option("--dpi", args->dpi,
                      "print resolution, recorded in PNGs and used with --size-mm (PNG only)")
          ->check(FiniteNumber())
          ->check(CLI::Range(50.0, 4800.0))
          ->capture_default_str();
  cmd->add_option("-o,--output", args->output, "output file, .png or .svg")->required();
  cmd->callback([args, dpi] {
    args->dpi_given = dpi->count() > 0;
    Run(*args);
  });
}

const CommandRegistration render_registration{"render", &AddRenderCommand};

}  // namespace

}  // namespace pintag::cli
