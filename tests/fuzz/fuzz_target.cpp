// One libFuzzer executable (fuzz_<name>, built with OMNISLAM_FUZZ=ON): the entry point named by
// OMNISLAM_FUZZ_TARGET, from the table of entry_points.cpp.
#include <cstdio>
#include <cstdlib>

#include "entry_points.h"

namespace {

omnislam::fuzz::EntryPoint entry() {
  static const omnislam::fuzz::Target* const t = omnislam::fuzz::findTarget(OMNISLAM_FUZZ_TARGET);
  if (t == nullptr) {
    std::fprintf(stderr, "fuzz: no target '%s'\n", OMNISLAM_FUZZ_TARGET);
    std::abort();
  }
  return t->entry;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  entry()(data, size);
  return 0;
}
