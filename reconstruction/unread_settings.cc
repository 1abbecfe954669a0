#include "reconstruction/unread_settings.h"

#include <algorithm>
#include <vector>

namespace weathergs::reconstruction {

namespace {

// The last iteration of the run at which the trainer densifies (and prunes): the largest multiple of
// the interval inside (densify_from, densify_until) and within the run; 0 when there is none.
int last_densification(const TrainOptions& e) {
  const int end = std::min(e.densify_until - 1, e.iterations);
  const int last = end / e.densification_interval * e.densification_interval;
  return last > e.densify_from ? last : 0;
}

}  // namespace

std::optional<UnreadSetting> unread_setting(const TrainOptions& options, const RunContext& context,
                                            const std::function<bool(const std::string& key)>& is_set) {
  const TrainOptions e = options.effective();
  struct Rule {
    std::vector<const char*> keys;
    bool unread;
    std::string why;
  };
  const int densified = last_densification(e);
  const int last_blend_prune = options.blend_prune_at.empty() ? 0 : options.blend_prune_at.back();
  const std::vector<Rule> rules = {
      {{"full_resolution_at"}, options.downsample_start == 1,
       "only the resolution schedule reads it, and this run trains at full resolution throughout (downsample_start 1)"},
      {{"distractor_opacity_weight"}, options.distractors_per_view == 0,
       "the opacity penalty of desplat's distractor Gaussians, and this run has none (distractors_per_view 0)"},
      {{"in_the_wild_from", "visibility_weight"}, !options.in_the_wild,
       "only gs-w-lite (in_the_wild) reads it, and this run is not one"},
      {{"in_the_wild_from"}, options.in_the_wild && options.in_the_wild_from >= options.iterations,
       "the visibility maps would start after the run's last iteration (" + std::to_string(options.iterations) + ")"},
      {{"random_init", "random_init_count", "random_init_near_m", "random_init_far_m"}, context.from_points,
       "the run starts from SfM points, so the random initialization never runs"},
      {{"mask_normalization"}, !context.loss_mask, "it normalises a masked loss, and this run's loss has no mask"},
      {{"densify_from", "densify_until", "densification_interval", "densify_grad_threshold", "percent_dense"},
       densified == 0,
       "no densification step falls inside the run (densify_from " + std::to_string(e.densify_from) + ", densify_until " +
           std::to_string(e.densify_until) + ", every " + std::to_string(e.densification_interval) + ", " +
           std::to_string(e.iterations) + " iterations)"},
      {{"large_prune", "large_prune_from", "max_world_size"}, densified <= e.large_prune_from,
       "the large-Gaussian prune runs at densification steps after large_prune_from (" +
           std::to_string(e.large_prune_from) + " in this run), and the last one is at iteration " +
           std::to_string(densified)},
      {{"blend_prune_threshold"}, options.blend_prune_at.empty(),
       "only the blend-weight prune reads it, and this run has none (blend_prune_at empty)"},
      {{"blend_prune_at"}, last_blend_prune > options.iterations,
       "holds " + std::to_string(last_blend_prune) + ", past the run's " + std::to_string(options.iterations) +
           " iterations: that prune would never run"},
      {{"position_lr_hold_until"}, options.position_lr_hold_until > options.iterations,
       "is past the run's " + std::to_string(options.iterations) + " iterations, which end the hold anyway"},
      {{"max_screen_size_px"}, true,
       "the screen-size prune is inert, as in the reference (docs/reconstruction.md): no value changes the run"},
  };
  for (const Rule& r : rules)
    if (r.unread)
      for (const char* key : r.keys)
        if (is_set(key)) return UnreadSetting{key, r.why};
  return std::nullopt;
}

}  // namespace weathergs::reconstruction
