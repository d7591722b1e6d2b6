// The oracle association of research/mrclam-diagnosis.md: a copy of a log written by
// omnislam-import-mrclam in which each OMNI_FEATURES feature's colour_a = (subject of its barcode, 0, 0)
// (0 for a code of no subject), read from the frame's GROUND_TRUTH_FEATURE_LABELS source codes and the
// dataset's Barcodes.dat. omnislam-slam with filter.descriptor_gate 0.5 then associates only sightings of
// one subject: the filter with known identities. Every other event is copied unchanged.
//   research_mrclam_subject_as_colour DATASET_DIR IN.lcm OUT.lcm
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "mrclam_files.h"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/log_writer.h"

using namespace omnislam;

namespace {

// Per OMNI_FEATURES seq, the source code of each feature (from its labels).
std::map<int64_t, std::vector<int32_t>> codesByFrame(const std::string& in) {
  std::map<int64_t, std::vector<int32_t>> out;
  for (const auto& lab : lcmio::readChannel<feature_labels_t>(in, channels::kGroundTruthFeatureLabels))
    out[lab.features_seq] = lab.source_code;
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: research_mrclam_subject_as_colour DATASET_DIR IN.lcm OUT.lcm\n";
    return 2;
  }
  try {
    lcmio::requireDistinctFiles(argv[2], argv[3], "OUT.lcm");
    std::map<int, int> subject_of_code;
    for (const auto& b : mrclam::readBarcodes(std::string(argv[1]) + "/Barcodes.dat"))
      subject_of_code[b.barcode] = b.subject;
    const auto codes = codesByFrame(argv[2]);
    lcmio::LogWriter out(argv[3]);
    int64_t rewritten = 0, unlabelled = 0;
    lcmio::forEachEvent(argv[2], [&](const lcmio::LogEvent& ev) {
      auto f = ev.channel == channels::kOmniFeatures ? lcmio::decodeAs<features_t>(ev) : std::nullopt;
      const auto it = f ? codes.find(f->seq) : codes.end();
      if (!f || it == codes.end() || it->second.size() != f->features.size()) {
        unlabelled += f.has_value();
        out.write(ev.log_utime, ev.channel, ev.data.data(), static_cast<int32_t>(ev.data.size()));
        return;
      }
      for (size_t i = 0; i < f->features.size(); ++i) {
        const auto s = subject_of_code.find(it->second[i]);
        f->features[i].colour_a[0] = s == subject_of_code.end() ? 0.0f : static_cast<float>(s->second);
      }
      out.write(ev.log_utime, ev.channel, *f);
      ++rewritten;
    });
    out.commit();
    std::cerr << "research_mrclam_subject_as_colour: " << rewritten << " frames given their subjects, " << unlabelled
              << " frames without labels copied unchanged\n";
    return unlabelled == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "research_mrclam_subject_as_colour: " << e.what() << "\n";
    return 1;
  }
}
