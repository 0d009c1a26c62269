// The names each choice of a kincald config file has (source: sim, pose.method: lowe, ...),
// and their lists for messages and the key reference; private to config.cc's loaders.
#pragma once

#include <array>
#include <string>
#include <string_view>

#include "kincal/daemon/config.h"

namespace kincal::daemon::config_internal {

template <typename E>
struct Named {
  std::string_view name;
  E value;
};
constexpr std::array<Named<SourceKind>, 4> kSourceNames{{{"sim", SourceKind::kSim},
                                                         {"v4l2", SourceKind::kV4l2},
                                                         {"libcamera", SourceKind::kLibcamera},
                                                         {"replay", SourceKind::kReplay}}};
constexpr std::array<Named<PoseMethod>, 2> kPoseMethodNames{
    {{"ground_plane", PoseMethod::kGroundPlane}, {"lowe", PoseMethod::kLowe}}};
constexpr std::array<Named<ControlStamp>, 3> kControlStampNames{
    {{"receive", ControlStamp::kReceive},
     {"sender", ControlStamp::kSender},
     {"mapped", ControlStamp::kMapped}}};
constexpr std::array<Named<FrameEncoding>, 3> kFrameEncodingNames{
    {{"raw", FrameEncoding::kRaw}, {"png", FrameEncoding::kPng}, {"jpeg", FrameEncoding::kJpeg}}};
// Pixel formats a camera can be asked for (PNG is only a recorded frame's encoding).
constexpr std::array<Named<PixelFormat>, 5> kCameraFormatNames{{{"GREY", PixelFormat::kGrey},
                                                                {"YUYV", PixelFormat::kYuyv},
                                                                {"MJPG", PixelFormat::kMjpeg},
                                                                {"BGR3", PixelFormat::kBgr24},
                                                                {"RGB3", PixelFormat::kRgb24}}};

template <typename E, size_t N>
std::string_view NameOf(const std::array<Named<E>, N>& table, E value) {
  for (const auto& n : table) {
    if (n.value == value) return n.name;
  }
  return "?";
}

template <typename E, size_t N>
std::string NameList(const std::array<Named<E>, N>& table) {
  std::string list;
  for (size_t i = 0; i < N; ++i) {
    list += (i == 0 ? "" : (i + 1 == N ? " or " : ", ")) + std::string(table[i].name);
  }
  return list;
}

}  // namespace kincal::daemon::config_internal
