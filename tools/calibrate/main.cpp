// omnislam-calibrate: intrinsic calibration of an omnidirectional camera from a folder of
// checkerboard images, with cv::omnidir (Mei) or cv::fisheye (Kannala-Brandt); writes the
// FileStorage YAML that the features config reads with `camera.model: auto` (docs/user/calibration.md).
#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <regex>

#include "board_calibration.h"
#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/vision/image_files.h"

using namespace omnislam;

namespace {

/// The fewest boards the tool calibrates from, by default: omnidir's 10 intrinsics and 6 pose
/// parameters per view need views spread over the image; OpenCV's sample stops below 3.
constexpr int kDefaultMinBoards = 5;

/// "COLSxROWS" with each in [lo, hi], as a CLI11 check.
CLI::Validator gridSize(int lo, int hi) {
  return CLI::Validator(
      [lo, hi](std::string& s) -> std::string {
        std::smatch m;
        if (!std::regex_match(s, m, std::regex(R"((\d{1,4})x(\d{1,4}))")))
          return "'" + s + "' is not COLSxROWS, e.g. 9x6";
        const int a = std::stoi(m[1]), b = std::stoi(m[2]);
        if (a < lo || a > hi || b < lo || b > hi)
          return "'" + s + "': each of COLS and ROWS must be in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                 "]";
        return {};
      },
      "COLSxROWS");
}

cv::Size parseGrid(const std::string& s) {
  const size_t x = s.find('x');
  return {std::stoi(s.substr(0, x)), std::stoi(s.substr(x + 1))};
}

struct Options {
  std::string images, out, annotate, corners, squares, model = "omnidir", command;
  double square_m = 0.0;
  int min_boards = kDefaultMinBoards;
};

struct Found {
  std::vector<calib::BoardView> views;
  std::vector<std::filesystem::path> files;  ///< every image, in name order
  std::vector<int> view_of_file;             ///< index into views, -1: board not found
  cv::Size size;
};

Found findBoards(const Options& o, const calib::BoardSpec& board) {
  Found f;
  f.files = vision::listImageFiles(o.images);
  if (f.files.empty()) throw std::invalid_argument("--images '" + o.images + "' holds no image files");
  for (const auto& p : f.files) {
    const cv::Mat grey = cv::imread(p.string(), cv::IMREAD_GRAYSCALE);
    if (grey.empty()) throw std::invalid_argument("cannot decode the image '" + p.string() + "'");
    if (f.size.empty()) f.size = grey.size();
    if (grey.size() != f.size)
      throw std::invalid_argument("'" + p.string() + "' is " + std::to_string(grey.cols) + "x" +
                                  std::to_string(grey.rows) + ", the first image " + std::to_string(f.size.width) +
                                  "x" + std::to_string(f.size.height) + ": one camera, one image size");
    auto v = calib::detectBoard(grey, board);
    f.view_of_file.push_back(v ? static_cast<int>(f.views.size()) : -1);
    std::cout << p.filename().string() << ": " << (v ? std::string("board found (") + v->detector + ")" : "no board")
              << "\n";
    if (v) {
      v->file = p.filename().string();
      f.views.push_back(*v);
    }
  }
  if (static_cast<int>(f.views.size()) < o.min_boards) {
    std::string failed;
    for (size_t i = 0; i < f.files.size(); ++i)
      if (f.view_of_file[i] < 0) failed += (failed.empty() ? "" : ", ") + f.files[i].filename().string();
    throw std::invalid_argument("boards found in " + std::to_string(f.views.size()) + " of " +
                                std::to_string(f.files.size()) + " images, fewer than --min-boards " +
                                std::to_string(o.min_boards) + "; no board of " +
                                std::to_string(board.inner_corners.width) + "x" +
                                std::to_string(board.inner_corners.height) + " inner corners in: " + failed);
  }
  return f;
}

void report(const Found& f, const calib::Calibration& c, double seconds) {
  std::printf("model %s, %d of %zu images used, %.1f s\n",
              c.model == calib::LensModel::kOmnidir ? "omnidir" : "fisheye",
              static_cast<int>(std::count_if(c.views.begin(), c.views.end(), [](const auto& v) { return v.used; })),
              f.files.size(), seconds);
  std::printf("rms reprojection error %.4f px\n", c.rms_px);
  std::printf("fx %.3f fy %.3f cx %.3f cy %.3f skew %.5f px; D %.6g %.6g %.6g %.6g", c.K(0, 0), c.K(1, 1), c.K(0, 2),
              c.K(1, 2), c.K(0, 1), c.D[0], c.D[1], c.D[2], c.D[3]);
  if (c.model == calib::LensModel::kOmnidir) std::printf("; xi %.6f", c.xi);
  std::printf("\n");
  for (size_t i = 0; i < f.files.size(); ++i) {
    const int v = f.view_of_file[i];
    if (v < 0) std::printf("  %-28s no board\n", f.files[i].filename().string().c_str());
    else if (!c.views[static_cast<size_t>(v)].used)
      std::printf("  %-28s not used (dropped at initialisation)\n", f.files[i].filename().string().c_str());
    else
      std::printf("  %-28s rms %.4f px\n", f.files[i].filename().string().c_str(),
                  c.views[static_cast<size_t>(v)].rms_px);
  }
}

void writeAnnotated(const Options& o, const Found& f, const calib::Calibration& c, const calib::BoardSpec& board) {
  std::filesystem::create_directories(o.annotate);
  for (size_t i = 0; i < f.files.size(); ++i) {
    const int v = f.view_of_file[i];
    const cv::Mat img = cv::imread(f.files[i].string(), cv::IMREAD_COLOR);
    const cv::Mat a = calib::annotateView(img, v < 0 ? nullptr : &f.views[static_cast<size_t>(v)],
                                          v < 0 ? nullptr : &c.views[static_cast<size_t>(v)], board);
    const std::string path = o.annotate + "/" + f.files[i].stem().string() + ".png";
    if (!cv::imwrite(path, a)) throw std::invalid_argument("--annotate: cannot write '" + path + "'");
  }
}

int run(const Options& o) {
  calib::BoardSpec board;
  board.inner_corners = o.corners.empty() ? parseGrid(o.squares) - cv::Size(1, 1) : parseGrid(o.corners);
  board.square_m = o.square_m;
  std::cout << "board: " << board.inner_corners.width << "x" << board.inner_corners.height << " inner corners, "
            << board.square_m << " m squares\n";
  const Found f = findBoards(o, board);
  const auto t0 = std::chrono::steady_clock::now();
  const auto model = o.model == "omnidir" ? calib::LensModel::kOmnidir : calib::LensModel::kFisheye;
  const calib::Calibration c = calib::calibrate(f.views, board, f.size, model);
  report(f, c, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  char summary[160];
  std::snprintf(summary, sizeof(summary), "rms reprojection error %.4f px over %zu boards of %zu images", c.rms_px,
                f.views.size(), f.files.size());
  calib::writeCalibration(o.out, c, f.views,
                          {"omnislam-calibrate (docs/user/calibration.md), made with:", "  " + o.command, summary});
  std::cout << "wrote " << o.out << "\n";
  if (!o.annotate.empty()) writeAnnotated(o, f, c, board);
  return app::kOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-calibrate: camera intrinsics from checkerboard images (cv::omnidir or cv::fisheye)"};
  Options o;
  for (int i = 0; i < argc; ++i) o.command += (i ? " " : "") + std::string(i ? argv[i] : "omnislam-calibrate");
  cli.add_option("--images", o.images, "folder of checkerboard images (one camera, one size)")->required();
  auto* corners =
      cli.add_option("--corners", o.corners, "board size in INNER corners (where 4 squares meet), COLSxROWS")
          ->check(gridSize(2, 100));
  auto* squares =
      cli.add_option("--squares", o.squares, "board size in SQUARES, COLSxROWS (inner corners = squares - 1)")
          ->check(gridSize(3, 101));
  corners->excludes(squares);
  cli.add_option("--square-m", o.square_m, "side of one square [m]")->required()->check(app::FiniteRange(1e-4, 10.0));
  cli.add_option("--model", o.model, "omnidir (Mei, catadioptric or wide fish-eye) or fisheye (Kannala-Brandt)")
      ->check(CLI::IsMember({"omnidir", "fisheye"}));
  cli.add_option("--out", o.out, "calibration file to write (OpenCV FileStorage YAML)")->required();
  cli.add_option("--annotate", o.annotate, "folder for one annotated PNG per image (corners + reprojection)");
  cli.add_option("--min-boards", o.min_boards, "fewest images with the whole board to calibrate from")
      ->check(CLI::Range(3, 10000));
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  return app::runMain("omnislam-calibrate", [&]() -> int {
    if (o.corners.empty() == o.squares.empty())
      throw std::invalid_argument("give the board as --corners COLSxROWS (inner corners) or --squares COLSxROWS");
    return run(o);
  });
}
