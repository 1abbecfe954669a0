// The benchmark's expected dataset identities (scenes/expected/<profile>.json): what `generate`
// must produce for each benchmark variant, per profile, with the tools it was recorded with. A
// variant generated with the same settings is checked against it when generate finishes
// (docs/scenes.md, "One benchmark, bit for bit").
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/dataset_identity.h"
#include "core/json_reader.h"

namespace weathergs::capture {

// The tools that made a dataset's bytes.
struct ToolVersions {
  std::string blender;  // "3.4.1" (from the render's log)
  std::string colmap;   // "COLMAP 3.8" ("" when generated without COLMAP)
  Json to_json() const;
  bool operator==(const ToolVersions& o) const { return blender == o.blender && colmap == o.colmap; }
};

// The first line of `colmap help` ("COLMAP 3.8 -- ..." -> "COLMAP 3.8"); "" if it cannot be run.
std::string colmap_version(const std::string& executable);
// `blender -v`'s first line without "Blender " ("3.4.1"); "" if it cannot be run.
std::string blender_version(const std::string& executable);

// What decides a variant's bytes besides the scene file and the tools: the resolved weather spec
// (the dataset's generator.spec, seed and style included), the view count and whether the
// restoration targets and the SfM models are made. Two generations with equal settings must give
// equal identities.
struct GenerationSettings {
  Json weather_spec;  // null for a variant without weather
  int max_views = 0;
  bool targets = false;
  bool colmap = true;
  Json to_json() const;
  bool operator==(const GenerationSettings& o) const { return to_json() == o.to_json(); }
};

struct ExpectedIdentity {
  std::string variant;  // "<scene>_<weather>"
  GenerationSettings settings;
  ToolVersions made_with;
  std::string weathergs_commit;
  DatasetIdentity identity;
};

// The tool versions every expected identity in `expected_dir` (scenes/expected/) was made with, each
// once, in file order: "Blender 3.4.1, COLMAP 3.8". Empty when the folder has none.
std::vector<ToolVersions> expected_tool_versions(const std::string& expected_dir);
std::string describe(const ToolVersions& t);  // "Blender 3.4.1, COLMAP 3.8"

// "<folder of the scene file>/expected/<profile>.json".
std::string expected_identities_path(const std::string& scene_file, const std::string& profile);

// The entry for `variant`, or nullopt when the file or the entry is absent. A malformed file is an
// InputError naming it.
std::optional<ExpectedIdentity> read_expected_identity(const std::string& path, const std::string& variant);

// Adds or replaces the variant's entry (atomically; the other entries are kept).
void write_expected_identity(const std::string& path, const std::string& profile, const ExpectedIdentity& entry);

}  // namespace weathergs::capture
