// kincal export: the calibrated parameters with their sigma (and covariance) as YAML a
// robot's configuration can include, from a kincald checkpoint or the last
// kincal.params_t in an LCM log.
#include <sys/stat.h>

#include <fstream>
#include <iostream>
#include <kincal/params_t.hpp>
#include <sstream>

#include "commands.h"
#include "kincal/daemon/checkpoint.h"
#include "kincal/io/lcm_guard.h"
#include "kincal/io/lcm_log_reader.h"

namespace kincal::app {

Command AddExport(CLI::App& app) {
  struct Args {
    std::string checkpoint, log, channel = "KINCAL_PARAMS", out;
  };
  auto a = std::make_shared<Args>();
  auto* ck = app.add_option("--checkpoint", a->checkpoint, "kincald checkpoint (JSON)");
  auto* log = app.add_option("--log", a->log, "LCM log: its last kincal.params_t on --channel");
  ck->excludes(log);
  app.add_option("--channel", a->channel, "params channel in the log")->capture_default_str();
  app.add_option("--out", a->out, "YAML file (default: standard output)");
  return [a]() -> int {
    daemon::Checkpoint c;
    std::string source;
    if (!a->checkpoint.empty()) {
      c = daemon::ReadCheckpoint(a->checkpoint);
      source = a->checkpoint;
    } else if (!a->log.empty()) {
      struct stat st {};
      if (::stat(a->log.c_str(), &st) != 0) throw std::runtime_error(a->log + ": cannot open");
      LcmLogReader file(a->log);
      kincal::params_t last;
      bool found = false;
      int64_t bad = 0;
      LcmLogEvent e;
      while (file.Next(&e)) {
        const LcmLogEvent* ev = &e;
        if (ev->channel != a->channel) continue;
        kincal::params_t m;
        std::string why;
        if (!PlausibleParams(ev->data.data(), ev->data.size(), 1000, &why) ||
            m.decode(ev->data.data(), 0, static_cast<int>(ev->data.size())) < 0 ||
            m.num_params < 0 || m.covariance.size() != static_cast<size_t>(m.num_params)) {
          ++bad;
          continue;
        }
        last = std::move(m);
        found = true;
      }
      if (!found)
        throw std::runtime_error(a->log + ": no kincal.params_t on channel " + a->channel);
      if (bad > 0)
        std::cerr << "kincal export: " << bad << " undecodable events on " << a->channel
                  << " skipped\n";
      for (const auto& p : file.problems()) std::cerr << "kincal export: " << p << "\n";
      daemon::FillCheckpoint(last, {}, &c);
      source = a->log + " (" + a->channel + ")";
    } else {
      throw std::runtime_error("give --checkpoint FILE or --log FILE");
    }
    if (a->out.empty()) {
      daemon::WriteExportYaml(std::cout, c, source);
    } else {
      std::ostringstream out;
      daemon::WriteExportYaml(out, c, source);
      WriteOutput(a->out, out.str(), "export");
      std::cout << "wrote " << a->out << "\n";
    }
    return 0;
  };
}

}  // namespace kincal::app
