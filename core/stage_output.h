// What an earlier run left of one stage's output, as the part that owns the stage judges it against
// the settings it is asked for now. Each part answers for its own outputs (the AEF's images, the
// LED's masks, a 3DGS model, a radiance field) from the settings record it wrote beside them; the
// layer that composes stages only asks.
#pragma once

#include <string>

namespace weathergs {

struct StageOutput {
  enum class State {
    kAbsent,    // nothing usable: the stage runs (replacing any leftovers)
    kPartial,   // stopped part way with the same settings: the stage resumes from its checkpoint
    kComplete,  // made with the same settings: reused as it is
    kStale,     // made with other settings: refused, never mixed in
  };
  State state = State::kAbsent;
  std::string record;  // the settings record that was judged (its path)
  std::string why;     // kStale: the first setting that differs ("KEY: holds A, asked for B")
};

}  // namespace weathergs
