// Where the installed (or built) `weathergs` finds its data, and the environment overrides. Only the
// binary reads the environment; libraries take explicit paths in their options.
//
// Data directories, in order: next to the binary (<bin>/), then the install prefix's share folder
// (<bin>/../share/weathergs/). `cmake --install` puts blender_scripts/, scenes/ and, when the LPIPS
// weights were found at configure time, models/lpips/ there; the build tree mirrors that layout
// (build/share/weathergs), so a built and an installed binary behave alike.
#pragma once

#include <string>
#include <vector>

namespace weathergs::cli {

// The folder holding the running executable (/proc/self/exe).
std::string executable_dir();

// <bin>/ and <bin>/../share/weathergs/, in search order.
std::vector<std::string> data_dirs();

// The Blender scene script: `flag` if given, else $WEATHERGS_BLENDER_SCRIPT, else
// blender_scripts/render_scene.py in the data directories. InputError naming every place searched.
std::string find_blender_script(const std::string& flag);

// The Lens Effect Detector weights stem (<stem>.json + <stem>.bin): `flag` if given, else
// $WEATHERGS_LED_WEIGHTS, else models/led/led in the data directories (the repository's models/ is
// staged there). InputError naming every place searched.
std::string find_led_weights(const std::string& flag);

// The learned AEF's weights folder (derain, desnow and selector .json/.bin): `flag` if given, else
// $WEATHERGS_AEF_WEIGHTS, else models/aef in the data directories. InputError naming every place searched.
std::string find_aef_weights(const std::string& flag);

// Where to look for the LPIPS model, in order: `flag` alone if given, else $WEATHERGS_LPIPS_MODEL alone
// if set, else models/lpips in the data directories (the repository's models/lpips is staged there).
std::vector<std::string> lpips_model_search(const std::string& flag);

// Cache of clean renders: `flag` if given, else $WEATHERGS_CACHE, $XDG_CACHE_HOME/weathergs,
// ~/.cache/weathergs. InputError when none can be determined.
std::string cache_dir(const std::string& flag);

}  // namespace weathergs::cli
