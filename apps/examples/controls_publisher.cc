// The ten-line C++ publisher of docs/ros.md: `t,omega_l,omega_r` lines on stdin to
// kincal.controls_t on KINCAL_CONTROLS (LCM's default URL, or $LCM_DEFAULT_URL).
#include <iostream>
#include <kincal/controls_t.hpp>
#include <lcm/lcm-cpp.hpp>
int main() {
  lcm::LCM lcm;
  kincal::controls_t m{};
  m.schema_version = 1, m.model = "diffdrive", m.num_controls = 2;
  m.names = {"omega_l", "omega_r"}, m.values = {0.0, 0.0};
  std::cin.ignore(1 << 20, '\n');  // the header line "t,omega_l,omega_r"
  for (double t;
       std::cin >> t && std::cin.ignore() >> m.values[0] && std::cin.ignore() >> m.values[1];) {
    m.utime = m.sender_utime = static_cast<int64_t>(t * 1e6);  // the robot's clock
    lcm.publish("KINCAL_CONTROLS", &m);
  }
}
