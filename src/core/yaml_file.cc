#include "kincal/yaml_file.h"

#include <map>

#include "kincal/text.h"

namespace kincal {
namespace {

std::string Line(const YAML::Mark& m) { return std::to_string(m.line + 1); }

// The first key that a map under `n` holds twice, named with the keys above it
// ("controls.low"); an empty status when there is none.
Status RepeatedKey(const YAML::Node& n, const std::string& path, const std::string& above) {
  if (n.IsSequence()) {
    for (const YAML::Node& item : n) {
      if (Status s = RepeatedKey(item, path, above); !s.ok()) return s;
    }
    return Status();
  }
  if (!n.IsMap()) return Status();
  std::map<std::string, YAML::Mark> seen;
  for (const auto& kv : n) {
    if (!kv.first.IsScalar()) continue;  // a complex key: compared by nobody
    const std::string key = above.empty() ? kv.first.Scalar() : above + "." + kv.first.Scalar();
    const auto [first, fresh] = seen.emplace(kv.first.Scalar(), kv.first.Mark());
    if (!fresh) {
      return Status::Error(path + ":" + Line(kv.first.Mark()) + ": key '" + key +
                           "' is set twice (first on line " + Line(first->second) +
                           "); YAML keys are unique: keep the one you mean");
    }
    if (Status s = RepeatedKey(kv.second, path, key); !s.ok()) return s;
  }
  return Status();
}

}  // namespace

StatusOr<YAML::Node> LoadYamlFile(const std::string& path, std::string_view what) {
  const StatusOr<std::string> text = ReadTextFile(path, what);
  if (!text.ok()) return text.status();
  YAML::Node root;
  try {
    root = YAML::Load(text.value());
  } catch (const YAML::Exception& e) {
    return Status::Error(path + ":" + Line(e.mark) + ": " + e.msg);
  }
  if (Status s = RepeatedKey(root, path, ""); !s.ok()) return s;
  return root;
}

}  // namespace kincal
