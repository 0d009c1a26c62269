// kincald's configuration: the documented examples load into typed options, choices are
// parsed once into their enums, and a wrong value names the file, the line, the key and
// what is expected.
#include "kincal/daemon/config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "daemon/daemon_test_util.h"
#include "source_dir.h"
#include "windows_text.h"

namespace kincal::daemon {
namespace {

const std::string kConfigDir = ::kincal::testing::SourceDir() + "/config";

std::string WriteConfig(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::temp_directory_path() / "kincal_config_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path) << text;
  return path;
}

std::string LoadError(const std::string& path) {
  const StatusOr<DaemonConfig> c = ReadDaemonConfig(path);
  return c.ok() ? "" : c.status().message();
}

DaemonConfig Load(const std::string& path) { return ReadDaemonConfig(path).value(); }

std::string ValidError(const DaemonConfig& c) {
  std::string error;
  return c.IsValid(&error) ? "" : error;
}

TEST(Config, DocumentedExamplesLoadIntoTypedOptions) {
  const DaemonConfig sim = Load(kConfigDir + "/kincald_sim.yaml");
  std::string error;
  EXPECT_TRUE(sim.IsValid(&error)) << error;
  EXPECT_EQ(sim.source, SourceKind::kSim);
  EXPECT_EQ(sim.pose.method, PoseMethod::kGroundPlane);
  EXPECT_EQ(sim.robot.control_stamp, ControlStamp::kMapped);
  EXPECT_EQ(sim.robot.model, "diffdrive");
  EXPECT_DOUBLE_EQ(sim.robot.guess.at("d"), 0.160);
  EXPECT_DOUBLE_EQ(sim.camera.nadir_height_m, 2.0);
  // Relative paths are relative to the file's folder.
  EXPECT_EQ(sim.sim.scenario, kConfigDir + "/sim_daemon.yaml");
  const DaemonConfig v4l2 = Load(kConfigDir + "/kincald_v4l2.yaml");
  EXPECT_TRUE(v4l2.IsValid(&error)) << error;
  EXPECT_EQ(v4l2.source, SourceKind::kV4l2);
  EXPECT_EQ(SourceName(v4l2.source), "v4l2");
  // The batch tier's section (docs/daemon.md, "Two tiers").
  EXPECT_TRUE(v4l2.calibration.enabled);
  EXPECT_DOUBLE_EQ(v4l2.calibration.every_s, 60.0);
  EXPECT_DOUBLE_EQ(v4l2.calibration.first_s, 30.0);
  EXPECT_EQ(v4l2.calibration.max_poses, 108000);
  EXPECT_EQ(v4l2.calibration.max_controls, 432000);
  EXPECT_EQ(v4l2.lcm.calibration_channel, "KINCAL_CALIBRATION");
}

TEST(Config, EveryChoiceParsesFromItsName) {
  const std::string path = WriteConfig("choices.yaml", R"(source: replay
replay: {path: run.lcm}
v4l2: {pixel_format: MJPG}
libcamera: {pixel_format: RGB3}
pose: {method: lowe}
robot: {control_stamp: sender}
record: {frame_encoding: png}
)");
  const DaemonConfig c = Load(path);
  EXPECT_EQ(c.source, SourceKind::kReplay);
  EXPECT_EQ(c.v4l2.pixel_format, PixelFormat::kMjpeg);
  EXPECT_EQ(c.libcamera.pixel_format, PixelFormat::kRgb24);
  EXPECT_EQ(c.pose.method, PoseMethod::kLowe);
  EXPECT_EQ(c.robot.control_stamp, ControlStamp::kSender);
  EXPECT_EQ(c.record.frame_encoding, FrameEncoding::kPng);
  EXPECT_EQ(FrameEncodingName(c.record.frame_encoding), "png");
  EXPECT_EQ(FrameEncodingName(FrameEncoding::kJpeg), "jpeg");
  EXPECT_EQ(PoseMethodName(c.pose.method), "lowe");
  EXPECT_EQ(ControlStampName(c.robot.control_stamp), "sender");
}

// Issue 34: a config saved by a Windows editor (CRLF, a UTF-8 byte-order mark) reads as its
// LF twin; so does one with a lone CR (yaml-cpp took the comment on a CR line to run on,
// and the keys after it were lost) and one in UTF-16.
TEST(Config, CrlfAndByteOrderMarkReadAsPlainText) {
  const std::string text =
      "# a replay\nsource: replay  # from a log\nreplay: {path: run.lcm}\npose:\n  method: lowe\n"
      "robot:\n  model: diffdrive\n  fixed: {d: 0.3}\n";
  for (const auto& [system, other] : ::kincal::testing::OtherSystemsText(text)) {
    const DaemonConfig c = Load(WriteConfig("crlf.yaml", other));
    EXPECT_EQ(c.source, SourceKind::kReplay) << system;
    EXPECT_TRUE(c.replay.path.ends_with("/run.lcm")) << system << ": " << c.replay.path;
    EXPECT_EQ(c.pose.method, PoseMethod::kLowe) << system;
    EXPECT_EQ(c.robot.model, "diffdrive") << system;
    ASSERT_EQ(c.robot.fixed.count("d"), 1u) << system;
    EXPECT_EQ(c.robot.fixed.at("d"), 0.3) << system;
  }
}

TEST(Config, AWrongChoiceNamesFileLineKeyAndTheChoices) {
  const std::string path = WriteConfig("bad_choice.yaml", "source: sim\npose:\n  method: pnp\n");
  EXPECT_EQ(LoadError(path),
            path + ":3: key 'pose.method': expected ground_plane or lowe, got 'pnp'");
  const std::string fmt = WriteConfig("bad_format.yaml", "v4l2:\n  pixel_format: PNG\n");
  EXPECT_EQ(
      LoadError(fmt),
      fmt + ":2: key 'v4l2.pixel_format': expected GREY, YUYV, MJPG, BGR3 or RGB3, got 'PNG'");
  const std::string src = WriteConfig("bad_source.yaml", "source: usb\n");
  EXPECT_EQ(LoadError(src),
            src + ":1: key 'source': expected sim, v4l2, libcamera or replay, got 'usb'");
}

// The same through the daemon's own checks, on every shipped config and on bad files.
TEST(DaemonConfig, EveryShippedConfigLoadsAndValidates) {
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(kConfigDir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("kincald_", 0) != 0) continue;
    SCOPED_TRACE(name);
    DaemonConfig c;
    ASSERT_EQ(LoadError(e.path().string()), "");
    c = Load(e.path().string());
    EXPECT_EQ(ValidError(c), "");
    ++n;
  }
  EXPECT_GE(n, 4);  // sim, v4l2, libcamera, thesis
}

TEST(DaemonConfig, UnknownKeyNamesFileLineAndTheKnownKeys) {
  const std::string path = test_util::TempPath("bad.yaml");
  std::ofstream(path) << "source: sim\nfilter:\n  type: dd2\n  kappa: 3\n";
  const std::string error = LoadError(path);
  EXPECT_NE(error.find("bad.yaml:4: unknown key 'filter.kappa'"), std::string::npos) << error;
  EXPECT_NE(error.find("max_pose_gap_s"), std::string::npos) << error;
}

TEST(DaemonConfig, WrongTypeAndBadValuesAreNamed) {
  const std::string path = test_util::TempPath("bad_type.yaml");
  std::ofstream(path) << "v4l2:\n  width: wide\n";
  const std::string error = LoadError(path);
  EXPECT_NE(error.find("bad_type.yaml:2: key 'v4l2.width'"), std::string::npos) << error;
  DaemonConfig c;
  c.source = SourceKind::kV4l2;
  c.v4l2.buffers = 2;
  EXPECT_NE(ValidError(c), "");
  c = DaemonConfig{};
  c.robot.guess["wheel_radius"] = 0.1;
  EXPECT_NE(ValidError(c).find("no parameter 'wheel_radius'"), std::string::npos) << ValidError(c);
}

// A number that is not finite (YAML's .nan and .inf) is refused where it is read, for every
// key; a negative or NaN sim.speed (the config's or --speed's) by the source's own check.
TEST(DaemonConfig, NonFiniteNumbersAndANegativeSpeedAreNamed) {
  const std::string nan = WriteConfig("nan_speed.yaml", "source: sim\nsim:\n  speed: .nan\n");
  EXPECT_EQ(LoadError(nan), nan + ":3: key 'sim.speed': finite numbers expected");
  const std::string inf = WriteConfig("inf_height.yaml", "camera:\n  nadir_height_m: .inf\n");
  EXPECT_NE(LoadError(inf).find(":2: key 'camera.nadir_height_m': finite numbers expected"),
            std::string::npos)
      << LoadError(inf);
  // A guess in a map, as read (it once reached the filter's prior and stopped kincald on a
  // failed check), and as set in code.
  const std::string guess =
      WriteConfig("nan_guess.yaml", "source: sim\nrobot:\n  guess: {r_l: .nan}\n");
  EXPECT_EQ(LoadError(guess), guess + ":3: key 'robot.guess': finite numbers expected");
  DaemonConfig c;
  c.robot.guess["r_l"] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(ValidError(c), "robot.guess: 'r_l' must be a finite number, not inf");
  c = DaemonConfig{};
  c.source = SourceKind::kSim;
  c.sim.speed = -3;
  EXPECT_NE(ValidError(c).find("sim.speed (or --speed) must be >= 0"), std::string::npos)
      << ValidError(c);
  c.sim.speed = std::nan("");
  EXPECT_NE(ValidError(c).find("sim.speed (or --speed) must be >= 0"), std::string::npos);
}

// robot.fixed: read from YAML, and a name that is not one of the model's parameters, or
// holding all of them, is an error naming them.
TEST(DaemonConfig, RobotFixedIsReadAndChecked) {
  const std::string dir = ::testing::TempDir();
  const std::string path = dir + "/fixed.yaml";
  std::ofstream(path) << "robot:\n  model: bicycle\n  fixed: {wheelbase: 0.33}\n";
  const StatusOr<DaemonConfig> read = ReadDaemonConfig(path);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->robot.fixed.at("wheelbase"), 0.33);
  DaemonConfig c;
  c.robot.model = "bicycle";
  c.robot.fixed = {{"wheel_base", 0.33}};
  std::string error;
  EXPECT_FALSE(c.robot.IsValid(&error));
  EXPECT_NE(error.find("its parameters: k_v, k_steer, steer_offset, wheelbase"), std::string::npos)
      << error;
  c.robot.fixed = {{"k_v", 1}, {"k_steer", 1}, {"steer_offset", 0}, {"wheelbase", 0.3}};
  EXPECT_FALSE(c.robot.IsValid(&error));
  EXPECT_NE(error.find("nothing is left to calibrate"), std::string::npos) << error;
  // A held or guessed value below the parameter's physical bound: a held wheelbase of 0 (a
  // held track of 0 on a diffdrive) ran to the end publishing NaN estimates.
  c.robot.fixed = {{"wheelbase", 0.0}};
  EXPECT_FALSE(c.robot.IsValid(&error));
  EXPECT_EQ(error, "robot.fixed: 'wheelbase' must be >= 0.001 m (its physical bound), not 0");
  c.robot.fixed = {};
  c.robot.guess = {{"k_v", 1.0}, {"wheelbase", -0.33}};
  EXPECT_FALSE(c.robot.IsValid(&error));
  EXPECT_EQ(error, "robot.guess: 'wheelbase' must be >= 0.001 m (its physical bound), not -0.33");
}

// The loaders are the one list of the keys: each key DaemonConfigKeys lists, written alone
// with its listed default, loads and gives the default config back; a key it does not list
// is refused. (docs/config_keys.md is this list: cli.config_keys_documented.)
TEST(DaemonConfig, EveryListedKeyLoadsWithItsDefault) {
  const std::vector<ConfigKey> keys = DaemonConfigKeys();
  ASSERT_GT(keys.size(), 100u);
  int checked = 0;
  for (const ConfigKey& k : keys) {
    SCOPED_TRACE(k.key);
    std::string value = k.default_value;
    if (const size_t names = value.find(" ("); names != std::string::npos) value.resize(names);
    const size_t dot = k.key.find('.');
    const std::string text =
        dot == std::string::npos
            ? k.key + ": " + value + "\n"
            : k.key.substr(0, dot) + ":\n  " + k.key.substr(dot + 1) + ": " + value + "\n";
    const std::string path = WriteConfig("key.yaml", text);
    ASSERT_EQ(LoadError(path), "") << text;
    ++checked;
  }
  EXPECT_EQ(checked, static_cast<int>(keys.size()));
  const auto has = [&keys](const std::string& key, const std::string& value) {
    for (const ConfigKey& k : keys) {
      if (k.key == key) return k.default_value == value;
    }
    return false;
  };
  EXPECT_TRUE(has("preview.rate_hz", "5"));
  EXPECT_TRUE(has("source", "sim (sim, v4l2, libcamera or replay)"));
  EXPECT_TRUE(has("filter.pose_psd", "[0, 0, 0]"));
  EXPECT_NE(LoadError(WriteConfig("not_listed.yaml", "preview:\n  fps: 5\n")), "");
}

}  // namespace
}  // namespace kincal::daemon
