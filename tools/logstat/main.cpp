// omnislam-logstat: prints what an LCM log holds, channel by channel (counts, sequence gaps,
// undecodable or invalid events, span and rate in the messages' own time), then each process's last
// PROCESS_STATUS (received, published, undecodable, refused, missed; its detail and last error).
// Several files are read in order as one recording, with what was lost between them.
#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <set>

#include "logstat.h"
#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/image_msg.h"
#include "omnislam/lcmio/log_reader.h"

namespace {

/// Writes every valid OMNI_IMAGE frame of the logs as PNG into export_dir: the exit code.
int exportImages(const std::vector<std::string>& paths, const std::string& export_dir) {
  std::filesystem::create_directories(export_dir);
  int n = 0, failed = 0;
  std::set<std::string> names;
  for (const auto& path : paths)
    omnislam::lcmio::forEachEvent(path, [&](const omnislam::lcmio::LogEvent& ev) {
      if (ev.channel != omnislam::channels::kOmniImage) return;
      // Only what a process would accept: decodeImage trusts the sizes that validate checks.
      const auto msg = omnislam::lcmio::decodeValid<omnislam::image_t>(ev);
      if (!msg) return;  // counted as bad in the table
      std::string why;
      const auto img = omnislam::lcmio::decodeImage(*msg, &why);
      char name[96];
      std::snprintf(name, sizeof name, "/frame_%06lld.png", static_cast<long long>(msg->seq));
      if (!names.insert(name).second)  // a repeated seq: keep both, named by the log's event number
        std::snprintf(name, sizeof name, "/frame_%06lld_event_%lld.png", static_cast<long long>(msg->seq),
                      static_cast<long long>(ev.event_number));
      if (!img || !cv::imwrite(export_dir + name, *img)) {
        std::cerr << "omnislam-logstat: "
                  << (img ? "cannot write " + export_dir + name : "image seq " + std::to_string(msg->seq) + ": " + why)
                  << "\n";
        ++failed;
        return;
      }
      ++n;
    });
  std::cout << n << " images written to " << export_dir;
  if (failed > 0) std::cout << ", " << failed << " could not be (stderr)";
  std::cout << "\n";
  return failed > 0 ? omnislam::app::kFailure : 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-logstat: per-channel statistics of an omnislam LCM log"};
  std::vector<std::string> paths;
  cli.add_option("log", paths,
                 "LCM log file; several are read in order as one recording (the parts of a restarted recorder: "
                 "NAME.lcm NAME.part2.lcm ...), and what was lost between them is shown")
      ->required()
      ->check(CLI::ExistingFile);
  std::string export_dir;
  cli.add_option("--export-images", export_dir, "also write every OMNI_IMAGE frame as PNG into this folder");
  // A callback runs before the check of required options: --list-types needs no log.
  cli.add_flag_callback(
      "--list-types",
      [] {
        for (const auto& [channel, type] : omnislam::tools::contractChannels())
          std::cout << channel << " " << type << "\n";
        throw CLI::Success();
      },
      "print each channel of the contract it decodes and its message type, one per line, and exit");
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  return omnislam::app::runMain("omnislam-logstat", [&]() -> int {
    const auto summary = omnislam::tools::logStats(paths);
    for (size_t i = 0; i < paths.size(); ++i) std::cout << (i ? " " : "") << paths[i];
    std::cout << "\n" << omnislam::tools::formatStats(summary.channels);
    const std::string gaps = omnislam::tools::formatPartGaps(summary.gaps);
    if (!gaps.empty()) std::cout << "\n" << gaps;
    const std::string processes = omnislam::tools::formatProcesses(summary.processes);
    if (!processes.empty()) std::cout << "\n" << processes;
    if (!summary.unreadable.empty()) std::cout << "\nwarning: " << summary.unreadable << "\n";
    if (!export_dir.empty()) return exportImages(paths, export_dir);
    return 0;
  });
}
