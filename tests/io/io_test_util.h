// Helpers for the io tests: a scratch folder per test, files written into it, and LCM
// events appended with liblcm's own writer.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>
#include <vector>

#include "kincal/io/lcm_log_reader.h"
#include "kincal/io/recording.h"
#include "kincal/model.h"
#include "lcm_round_trip.h"

namespace kincal::testing {

// Appends one encoded LCM message to a log written with liblcm's own writer.
template <typename Msg>
void PutMessage(lcm::LogFile& log, const std::string& channel, const Msg& msg, int64_t utime) {
  std::vector<uint8_t> buf = Encoded(msg);
  lcm::LogEvent ev{};
  ev.timestamp = utime;
  ev.channel = channel;
  ev.datalen = static_cast<int32_t>(buf.size());
  ev.data = buf.data();
  log.writeEvent(&ev);
}

class IoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("kincal_io_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Write(const std::string& name, const std::string& text) {
    const auto p = (dir_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  std::string Error(const std::string& controls, const std::string& poses) {
    const StatusOr<Recording> r = ReadCsvRecording(Write("c.csv", controls), Write("p.csv", poses),
                                                   *MakeModel("unicycle").value());
    return r.ok() ? std::string("no error") : r.status().message();
  }
  std::filesystem::path dir_;
};

// Three events written by liblcm's own writer; the bytes of the file, for damaging.
inline std::string ThreeEventLog(const std::filesystem::path& dir, std::vector<int64_t>* offsets) {
  const std::string path = (dir / "three.lcm").string();
  {
    lcm::LogFile log(path, "w");
    for (int k = 0; k < 3; ++k) {
      std::vector<uint8_t> data(static_cast<size_t>(100 + k), static_cast<uint8_t>(k));
      lcm::LogEvent ev{};
      ev.timestamp = 1000 + k;
      ev.channel = "CH" + std::to_string(k);
      ev.datalen = static_cast<int32_t>(data.size());
      ev.data = data.data();
      log.writeEvent(&ev);
    }
  }
  // Header 28 bytes + channel 3 bytes + data.
  *offsets = {0, 28 + 3 + 100, 2 * (28 + 3) + 100 + 101};
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A log the test wrote, opened at its start; none (and the test failed) when it cannot be.
inline std::unique_ptr<LcmLogReader> OpenLog(const std::string& path) {
  std::unique_ptr<LcmLogReader> log;
  const Status opened = LcmLogReader::Open(path, &log);
  if (!opened.ok()) ADD_FAILURE() << opened.message();
  return log;
}

inline std::vector<LcmLogEvent> ReadAll(LcmLogReader& r) {
  std::vector<LcmLogEvent> out;
  LcmLogEvent e;
  while (r.Next(&e)) out.push_back(e);
  return out;
}

}  // namespace kincal::testing
