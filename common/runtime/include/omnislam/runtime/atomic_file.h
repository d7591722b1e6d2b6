// Whole files written atomically and durably, and read back whole: checkpoints, saved maps and the
// tools' output files. The standard library and POSIX only (library omnislam_atomic_file).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace omnislam::runtime {

/// Replaces the file at `path` by `size` bytes so that a reader, or a crash at any point, sees the old
/// file or the new one, never a part of either: a temporary file PATH.tmp.<pid> in the same folder is
/// written in full (a write interrupted by a signal is retried, a write that takes no byte is an
/// error), fsynced, renamed over PATH, and the folder is fsynced so that the rename itself is on disk.
/// On any failure the temporary file is removed and std::runtime_error says
/// "cannot write 'PATH': STEP: REASON" (STEP: create, write, fsync, close, rename, fsync of the folder;
/// REASON: the system's, strerror). A failure after the rename (the folder's fsync) leaves the new file
/// in place but not known to be on disk, and is reported all the same.
void writeFileAtomically(const std::string& path, const void* data, std::size_t size);

inline void writeFileAtomically(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  writeFileAtomically(path, bytes.data(), bytes.size());
}

/// The whole file; throws std::runtime_error naming the path and the system's reason.
std::vector<std::uint8_t> readWholeFile(const std::string& path);

}  // namespace omnislam::runtime
