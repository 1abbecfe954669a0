// The folder layout of a dataset (docs/formats.md), spelled once. Every part and
// every script builds dataset paths from these names; blender_scripts/ receive theirs through the
// job file that capture writes.
#pragma once

#include <string>

namespace weathergs {

namespace layout {
inline constexpr const char* kDatasetJson = "dataset.json";
inline constexpr const char* kCamerasJson = "cameras.json";
inline constexpr const char* kTransformsJson = "transforms.json";
inline constexpr const char* kImagesDir = "images";    // the inputs a method trains on (with weather)
inline constexpr const char* kCleanDir = "clean";      // ground truth without weather
inline constexpr const char* kDepthDir = "depth";      // planar depth of the clean scene, EXR
inline constexpr const char* kLensMaskDir = "masks/lens";
inline constexpr const char* kParticleMaskDir = "masks/particles";
inline constexpr const char* kLayersDir = "layers";    // optional float layers: layers/<name>/<view>.exr
inline constexpr const char* kLensCoverageLayer = "lens_coverage";  // the lens drops' blurred coverage, [0, 1]
// Restoration targets of the generator (optional): the weathered view without the particles (every
// other effect on), and the clean view with only the lens drops.
inline constexpr const char* kTargetNoParticlesDir = "targets/no_particles";
inline constexpr const char* kTargetLensOnlyDir = "targets/lens_only";
inline constexpr const char* kSparseDir = "sparse";    // COLMAP models of the input images
inline constexpr const char* kSparseModelDir = "sparse/0";
inline constexpr const char* kSparseCleanModelDir = "sparse_clean/0";  // the same from the clean images
inline constexpr const char* kLogsDir = "logs";        // tool logs (COLMAP, Blender), not data
inline constexpr const char* kImageExt = ".png";
inline constexpr const char* kDepthExt = ".exr";
}  // namespace layout

// The per-view files of a dataset.
enum class ImageKind { kImages, kClean, kDepth, kLensMask, kParticleMask, kTargetNoParticles, kTargetLensOnly };

const char* folder_of(ImageKind kind);     // relative to the dataset root, e.g. "masks/lens"
const char* extension_of(ImageKind kind);  // ".png" or ".exr"
const char* to_string(ImageKind kind);  // "images", "clean", "depth", "lens_mask", "particle_mask",
                                        // "target_no_particles", "target_lens_only"

// Planar depths at or beyond this many meters are background (no geometry), as is +inf.
inline constexpr float kBackgroundDepthM = 1e9f;
inline bool is_background_depth(float z) { return !(z < kBackgroundDepthM); }

}  // namespace weathergs
