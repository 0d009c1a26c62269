// kincal: the calibration tool. Thin front end over kincal::core; see `kincal --help`.
#include <cstdlib>
#include <exception>
#include <iostream>
#include <map>
#include <string>

#include "commands.h"
#include "kincal/effect.h"
#include "kincal/estimation/filter.h"
#include "kincal/model.h"
#include "options.h"

int main(int argc, char** argv) {
  // Before any image is decoded: OpenCV reads its limit once (an environment setting the
  // user made wins).
  setenv("OPENCV_IO_MAX_IMAGE_PIXELS", std::to_string(kincal::app::kMaxImagePixels).c_str(), 0);
  CLI::App app{"kincal: kinematic calibration of mobile robots from camera poses"};
  app.require_subcommand(1);
  std::map<CLI::App*, kincal::app::Command> commands;
  auto* models = app.add_subcommand("models", "list kinematic models, effects and filters");
  commands[models] = []() -> kincal::StatusOr<int> {
    for (const auto& name : kincal::ModelRegistry::Instance().Names()) {
      auto m = kincal::MakeModel(name).value();
      std::cout << "model " << name << ": " << m->description() << "\n  params:";
      for (const auto& p : m->params()) std::cout << " " << p.name << " [" << p.unit << "]";
      std::cout << "\n  controls:";
      for (const auto& c : m->controls()) std::cout << " " << c.name << " [" << c.unit << "]";
      std::cout << "\n";
    }
    for (const auto& name : kincal::EffectRegistry::Instance().Names()) {
      auto e = kincal::EffectRegistry::Instance().Create(name);
      std::cout << "effect " << name << " (" << kincal::ToString(e->stage())
                << "): " << e->description() << "\n  params:";
      for (const auto& p : e->params()) std::cout << " " << p.name << " [" << p.unit << "]";
      std::cout << "\n";
    }
    std::cout << "filters:";
    for (const auto& name : kincal::FilterRegistry::Instance().Names()) std::cout << " " << name;
    std::cout << "\n";
    return 0;
  };
  auto* reproduce = app.add_subcommand("reproduce", "reproduce a published experiment");
  commands[reproduce] = kincal::app::AddReproduce(*reproduce);
  auto* simulate = app.add_subcommand("simulate", "simulate a robot and calibrate it online");
  commands[simulate] = kincal::app::AddSimulate(*simulate);
  auto* analyze = app.add_subcommand(
      "analyze", "calibrate on measured data, find missing effects, report before/after");
  commands[analyze] = kincal::app::AddAnalyze(*analyze);
  auto* camcal = app.add_subcommand("camcal", "calibrate a camera from board images or points");
  commands[camcal] = kincal::app::AddCamcal(*camcal);
  auto* target = app.add_subcommand("target", "draw the printable marker target (SVG)");
  commands[target] = kincal::app::AddTarget(*target);
  auto* render = app.add_subcommand("render", "render the target with the synthetic camera (PNG)");
  commands[render] = kincal::app::AddRender(*render);
  auto* detect = app.add_subcommand("detect", "show what the marker detector finds in an image");
  commands[detect] = kincal::app::AddDetect(*detect);
  auto* floorcal = app.add_subcommand("floorcal", "camera pose above the floor from a board image");
  commands[floorcal] = kincal::app::AddFloorcal(*floorcal);
  auto* exp = app.add_subcommand(
      "export", "write calibrated parameters (with sigma) as YAML for a robot's config");
  commands[exp] = kincal::app::AddExport(*exp);
  auto* imp = app.add_subcommand("import", "a ROS 1 or ROS 2 bag to a kincal LCM log (rosbags)");
  commands[imp] = kincal::app::AddImport(*imp);
  auto* view =
      app.add_subcommand("view", "what kincald sees, live or from a recording, in the browser");
  commands[view] = kincal::app::AddView(*view);
  auto* plan = app.add_subcommand("plan", "how to drive a robot to calibrate it fastest");
  commands[plan] = kincal::app::AddPlan(*plan);
  kincal::app::RefuseNonFiniteNumbers(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  // The commands report errors as statuses; the catch is for what a library throws (an
  // allocation that fails), which is still said, not a crash.
  try {
    for (auto* sub : app.get_subcommands()) {
      const kincal::StatusOr<int> code = commands.at(sub)();
      if (code.ok()) return code.value();
      std::cerr << "kincal: error: " << code.status().message() << "\n";
      return 1;
    }
  } catch (const std::exception& e) {
    std::cerr << "kincal: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
