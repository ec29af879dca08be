// Committed regression images (tests/data/regressions/): frames of the benchmark sweep, cropped
// around their tag and saved losslessly with the truth, so that no change of the scene generator
// changes what is tested. Four folders, as zxing keeps black-box folders with a pass count and a
// misread budget:
//   read/            tags an earlier detector read only through a rule made for them: read them
//   misread-detect/  frames on which the detector once reported a wrong key: never again
//   misread-square/  tags the readers once turned into a wrong key on a square placed by the
//                    truth (plus recorded corner offsets): never again
//   search/          squares (truth plus recorded offsets) on which the model's codeword search
//                    once missed the codeword that explains the samples best: find it
// A frame that the detector of the day still misreads goes to a fifth folder, misread-open/, which
// no test reads (it would fail), until the fix's commit moves it to misread-detect/ (none is open).
// Each PNG has a JSON beside it: key, corners (C0 … C3, crop pixels), square offsets, source. The
// square offsets are one placement (four [dx, dy]) or a list of placements, when several jittered
// squares of one tag once gave a wrong key.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "pintag/detector/detector.hpp"
#include "reading/model_reader.hpp"
#include "reading/read_tag.hpp"

namespace pintag {
namespace {

struct RegressionCase {
  std::string name;
  cv::Mat bgr;
  int key = -1;
  std::array<cv::Point2d, 4> corners{};
  std::vector<std::array<cv::Point2d, 4>> placements;  ///< corner offsets of each square read
};

// Four [x, y] pairs: a case's corners, or one placement's offsets.
std::array<cv::Point2d, 4> FourPoints(const nlohmann::json& four) {
  std::array<cv::Point2d, 4> points;
  for (std::size_t i = 0; i < 4; ++i) {
    points[i] = {four.at(i).at(0).get<double>(), four.at(i).at(1).get<double>()};
  }
  return points;
}

std::vector<RegressionCase> LoadFolder(const std::string& folder) {
  const std::filesystem::path dir = std::filesystem::path(PINTAG_REGRESSIONS_DIR) / folder;
  std::vector<RegressionCase> cases;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".png") continue;
    RegressionCase c;
    c.name = entry.path().stem().string();
    c.bgr = cv::imread(entry.path().string(), cv::IMREAD_COLOR);
    std::ifstream in(std::filesystem::path(entry.path()).replace_extension(".json"));
    const nlohmann::json truth = nlohmann::json::parse(in);
    c.key = truth.at("key").get<int>();
    c.corners = FourPoints(truth.at("corners"));
    const nlohmann::json& offsets = truth.at("square_offsets");
    if (offsets.at(0).at(0).is_array()) {
      for (const nlohmann::json& placement : offsets) c.placements.push_back(FourPoints(placement));
    } else {
      c.placements.push_back(FourPoints(offsets));
    }
    cases.push_back(std::move(c));
  }
  std::sort(cases.begin(), cases.end(),
            [](const RegressionCase& a, const RegressionCase& b) { return a.name < b.name; });
  return cases;
}

// The squares a case is read on: its true corners moved by each recorded placement.
std::vector<std::array<cv::Point2d, 4>> PlacedSquares(const RegressionCase& c) {
  std::vector<std::array<cv::Point2d, 4>> squares;
  for (const std::array<cv::Point2d, 4>& offsets : c.placements) {
    std::array<cv::Point2d, 4>& square = squares.emplace_back();
    for (std::size_t i = 0; i < 4; ++i) square[i] = c.corners[i] + offsets[i];
  }
  return squares;
}

std::vector<int> Keys(const DetectResult& result) {
  std::vector<int> keys;
  for (const Detection& d : result.detections) {
    if (d.key) keys.push_back(d.key->value());
  }
  return keys;
}

bool Reports(const DetectResult& result, int key) {
  const std::vector<int> keys = Keys(result);
  return std::find(keys.begin(), keys.end(), key) != keys.end();
}

// The tags of read/ came from rules of the earlier readers (faint red pass, pairs of red blobs,
// dark squares, nearest codeword beyond the best-ranked few). The model reader decides most of them
// now, by a lead counted in independent chroma samples (reading/decision.hpp). The detector leaves
// three of the 15 unread (2026-11-30). Read on their true corners, the model refuses two because
// their fitted colours are not a tag's: seed 1 frame 469 (24 px, 0°, hard light) and seed 3 frame
// 269 (32 px, 55°). The third is seed 1 frame 711 (32 px, 65°, a narrow square): its right codeword
// leads by 106, but explains the samples 19 noise units worse than the free reading of its cells,
// and kMaxNarrowExcess allows 10. The least number read is held here, and no tag of the folder may
// be read as another key.
constexpr int kReadFolderMinRead = 12;

TEST(Regressions, ReadsTheTagsOfTheReadFolder) {
  const std::vector<RegressionCase> cases = LoadFolder("read");
  ASSERT_GE(cases.size(), 15U);
  const Detector detector;
  int read = 0;
  for (const RegressionCase& c : cases) {
    ASSERT_FALSE(c.bgr.empty()) << c.name;
    const std::vector<int> keys = Keys(detector.detect(c.bgr));
    for (const int key : keys) EXPECT_EQ(key, c.key) << c.name << ": a wrong key";
    if (std::find(keys.begin(), keys.end(), c.key) != keys.end()) {
      ++read;
    } else {
      std::printf("not read: %s\n", c.name.c_str());
    }
  }
  EXPECT_GE(read, kReadFolderMinRead) << "of " << cases.size();
}

// DetectorOptions::max_model_reads bounds the model reader per frame: with none allowed, the tags
// that only the model reads are not read, each such candidate is counted as skipped, and no model
// time is spent; with the default, those tags are read and the reads are counted.
TEST(Regressions, ModelReadsStayWithinTheFramesBudget) {
  const std::vector<RegressionCase> cases = LoadFolder("read");
  DetectorOptions none;
  none.max_model_reads = 0;
  const Detector without_model(none);
  const Detector with_default;
  int read_only_by_model = 0;
  for (const RegressionCase& c : cases) {
    const DetectResult spent = without_model.detect(c.bgr);
    const DetectResult full = with_default.detect(c.bgr);
    EXPECT_EQ(spent.timings.model_reads, 0) << c.name;
    EXPECT_EQ(spent.timings.model_fit_ms, 0.0) << c.name;
    EXPECT_LE(full.timings.model_reads + full.timings.model_rereads + full.timings.mosaic_rereads,
              with_default.options().max_model_reads)
        << c.name;
    if (!Reports(spent, c.key) && Reports(full, c.key)) {
      ++read_only_by_model;
      EXPECT_GT(spent.timings.model_skipped, 0) << c.name;
      EXPECT_GT(full.timings.model_reads, 0) << c.name;
    }
  }
  // Most of the folder's tags are small ones only the model reads.
  EXPECT_GE(read_only_by_model, 5);
}

DetectResult DetectWithModelReads(const cv::Mat& bgr, int reads) {
  DetectorOptions options;
  options.max_model_reads = reads;
  return Detector(options).detect(bgr);
}

// A model winner on a narrow square is kept only when two more reads from moved corners choose it
// too, and those reads come out of the frame's max_model_reads. The folder's narrow tags that the
// model reads need one read and two re-reads, then whatever the mosaic check asks: with one or two
// reads the winner is refused for want of its re-reads (and the candidate counted as skipped), with
// all of them it is reported.
TEST(Regressions, NarrowSquaresWinnersAreReadTwiceMoreFromTheFramesBudget) {
  const std::vector<RegressionCase> cases = LoadFolder("read");
  const Detector with_default;
  int kept_after_rereading = 0;
  for (const RegressionCase& c : cases) {
    const DetectResult full = with_default.detect(c.bgr);
    if (full.timings.model_rereads == 0 || !Reports(full, c.key)) continue;
    ++kept_after_rereading;
    ASSERT_EQ(full.timings.model_reads, 1) << c.name << ": the case should need one model read";
    EXPECT_EQ(full.timings.model_rereads, 2) << c.name;
    for (const int reads : {1, 2}) {
      const DetectResult short_of_rereads = DetectWithModelReads(c.bgr, reads);
      EXPECT_FALSE(Reports(short_of_rereads, c.key)) << c.name << " with " << reads << " reads";
      EXPECT_EQ(short_of_rereads.timings.model_reads, 1) << c.name;
      EXPECT_EQ(short_of_rereads.timings.model_rereads, reads - 1) << c.name;
      EXPECT_GE(short_of_rereads.timings.model_skipped, 1) << c.name;
    }
    const DetectResult enough = DetectWithModelReads(c.bgr, 3 + full.timings.mosaic_rereads);
    EXPECT_TRUE(Reports(enough, c.key)) << c.name;
    EXPECT_EQ(enough.timings.model_rereads, 2) << c.name;
  }
  EXPECT_GE(kept_after_rereading, 3);
}

// A model winner whose lead a demosaic's error could have made is kept only when a read through a
// Bayer mosaic of the detector's own accepts it again; those reads come out of max_model_reads
// too. With every read but the mosaic's the winner is refused and the candidate counted as
// skipped; with them it is reported.
TEST(Regressions, MosaicRereadsComeOutOfTheFramesBudget) {
  const std::vector<RegressionCase> cases = LoadFolder("read");
  const Detector with_default;
  int checked = 0;
  for (const RegressionCase& c : cases) {
    const DetectResult full = with_default.detect(c.bgr);
    // Frames whose mosaic re-reads all belong to the one tag the model read.
    if (full.timings.mosaic_rereads == 0 || full.timings.model_reads != 1 ||
        !Reports(full, c.key)) {
      continue;
    }
    ++checked;
    const int all = full.timings.model_reads + full.timings.model_rereads;
    const DetectResult short_of_mosaic = DetectWithModelReads(c.bgr, all);
    EXPECT_FALSE(Reports(short_of_mosaic, c.key)) << c.name;
    EXPECT_EQ(short_of_mosaic.timings.mosaic_rereads, 0) << c.name;
    EXPECT_GE(short_of_mosaic.timings.model_skipped, 1) << c.name;
    const DetectResult enough = DetectWithModelReads(c.bgr, all + full.timings.mosaic_rereads);
    EXPECT_TRUE(Reports(enough, c.key)) << c.name;
  }
  EXPECT_GE(checked, 3);
}

TEST(Regressions, NoWrongKeyOnFramesThatOnceGaveOne) {
  const std::vector<RegressionCase> cases = LoadFolder("misread-detect");
  ASSERT_GE(cases.size(), 10U);
  const Detector detector;
  for (const RegressionCase& c : cases) {
    ASSERT_FALSE(c.bgr.empty()) << c.name;
    for (const int key : Keys(detector.detect(c.bgr))) EXPECT_EQ(key, c.key) << c.name;
  }
}

TEST(Regressions, NoWrongKeyReadOnSquaresPlacedByTheTruth) {
  const std::vector<RegressionCase> cases = LoadFolder("misread-square");
  ASSERT_GE(cases.size(), 8U);
  for (const RegressionCase& c : cases) {
    ASSERT_FALSE(c.bgr.empty()) << c.name;
    for (const std::array<cv::Point2d, 4>& square : PlacedSquares(c)) {
      const stage::CandidateReading read =
          stage::ReadCandidate(c.bgr, ChromaUpsampling::kBoth, square, {});
      if (read.reading.payload.key) {
        EXPECT_EQ(read.reading.payload.key->value(), c.key) << c.name;
      }
    }
  }
}

// The winner is whichever scored codeword explains the samples best, so a codeword never scored
// cannot win however well it explains them. These squares once had the truth left out (eight cells
// from the winner, past the neighbourhood's seven) while it explained the samples better than the
// winner, which then stood one rule away from being accepted.
TEST(Regressions, TheCodewordSearchFindsTheCodewordThatExplainsTheSamplesBest) {
  const std::vector<RegressionCase> cases = LoadFolder("search");
  ASSERT_GE(cases.size(), 1U);
  for (const RegressionCase& c : cases) {
    ASSERT_FALSE(c.bgr.empty()) << c.name;
    for (const std::array<cv::Point2d, 4>& square : PlacedSquares(c)) {
      const reading::ModelReading read =
          reading::ReadThroughModel(c.bgr, ChromaUpsampling::kBoth, square);
      ASSERT_TRUE(read.fit.ok) << c.name << ": " << read.error;
      ASSERT_TRUE(read.decision.winner) << c.name;
      EXPECT_EQ(read.decision.winner->value(), c.key) << c.name;
    }
  }
}

}  // namespace
}  // namespace pintag
