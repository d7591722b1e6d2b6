// The image files of a folder, in name order (png, jpg/jpeg, pgm, ppm, bmp; case-insensitive).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace omnislam::vision {

/// Throws std::invalid_argument naming `dir` when it is not a directory. May return an empty list.
std::vector<std::filesystem::path> listImageFiles(const std::string& dir);

}  // namespace omnislam::vision
