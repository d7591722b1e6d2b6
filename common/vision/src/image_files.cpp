// Image files of a folder: see image_files.h.
#include "omnislam/vision/image_files.h"

#include <algorithm>
#include <cctype>
#include <stdexcept>

namespace omnislam::vision {

std::vector<std::filesystem::path> listImageFiles(const std::string& dir) {
  if (!std::filesystem::is_directory(dir)) throw std::invalid_argument("'" + dir + "' is not a directory");
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".ppm" || ext == ".bmp")
      files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace omnislam::vision
