// The bad-input corpus (reliability): every command of the real binary fed
// malformed and unknown-key JSON, wrong types and ranges, truncated and corrupt images, NaN depth, size
// mismatches, missing files, unwritable outputs, absurd parameters and a run folder from another
// version. Each case must exit 2, name the file / key / view in its message, and leave nothing at the
// output path. The fixtures are made here from one small valid dataset and one tiny trained run; the
// table below is the corpus (tests/data/bad/README.md lists it by command).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>

#include "core/atomic_file.h"
#include "core/colmap_model.h"
#include "core/dataset.h"
#include "core/image.h"
#include "core/json_reader.h"
#include "tests/core/test_util.h"
#include "tests/generator/test_scene.h"

namespace weathergs {
namespace {

namespace fs = std::filesystem;

struct Case {
  std::string name;
  std::function<void(const std::string& tmp)> setup;  // may be empty
  std::string args;     // after `weathergs --quiet`; $T = the scratch folder, $D = the valid dataset
  std::string message;  // a substring the error message must contain (file, key or view)
  std::string output;   // what must not exist afterwards (relative to $T), empty: none
};

std::string expand(std::string s, const std::string& tmp) {
  for (size_t p; (p = s.find("$D")) != std::string::npos;) s.replace(p, 2, tmp + "/data");
  for (size_t p; (p = s.find("$T")) != std::string::npos;) s.replace(p, 2, tmp);
  return s;
}

int run(const std::string& args, const std::string& log) {
  const int st = std::system((std::string(WEATHERGS_BINARY) + " --quiet " + args + " > '" + log + "' 2>&1").c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

// A copy of the valid dataset at $T/<name> with `edit` applied to one JSON file.
void patched(const std::string& tmp, const std::string& name, const std::string& file, const std::function<void(Json&)>& edit) {
  copy_tree(tmp + "/data", tmp + "/" + name);
  Json j = read_json_file(tmp + "/" + name + "/" + file);
  edit(j);
  write_file_atomic(tmp + "/" + name + "/" + file, j.dump());
}

void text(const std::string& path, const std::string& contents) {
  fs::create_directories(fs::path(path).parent_path());
  write_file_atomic(path, contents);
}

// A PNG signature and IHDR chunk (correct CRC) claiming width x height, then nothing: a reader must
// reject it from the header, before allocating pixels.
std::string png_header_only(uint32_t width, uint32_t height) {
  auto be32 = [](uint32_t v) {
    return std::string{char(v >> 24), char(v >> 16 & 255), char(v >> 8 & 255), char(v & 255)};
  };
  std::string chunk = "IHDR" + be32(width) + be32(height) + std::string{8, 2, 0, 0, 0};  // 8-bit RGB
  uint32_t crc = 0xffffffffu;
  for (unsigned char b : chunk) {
    crc ^= b;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return std::string("\x89PNG\r\n\x1a\n", 8) + be32(13) + chunk + be32(~crc);
}

Json results_json() {
  return Json::parse(R"({"format": "weathergs-results", "version": 1, "method": "m", "dataset": "d", "scene": "s",
    "weather": "rain", "protocol": {"ssim": "gaussian11_sigma1.5_valid", "lpips": null, "quantize_uint8": true,
    "split": "test", "mask": null}, "metrics": {"psnr": 20.0, "ssim": 0.5, "lpips": null},
    "per_view": {"000": {"psnr": 20.0, "ssim": 0.5, "lpips": null}}, "method_info": {},
    "sha256": {"renders": "x", "ground_truth": "y"}})");
}

// A copy of the valid dataset at $T/pts with SfM points in sparse/0: runs on it start from them.
void with_points(const std::string& tmp) {
  if (fs::exists(tmp + "/pts")) return;
  copy_tree(tmp + "/data", tmp + "/pts");
  ColmapModel m = colmap_model_from_cameras(read_dataset(tmp + "/pts").cameras);
  for (int i = 0; i < 20; ++i) {
    ColmapPoint3D p;
    p.id = i + 1;
    p.xyz = Eigen::Vector3d(0.2 * i - 2, 8, 0.1 * i);
    p.rgb = Eigen::Vector3d(120, 100, 80);
    p.track = {{1, 0}, {2, 0}};
    m.points.push_back(p);
  }
  fs::create_directories(tmp + "/pts/sparse/0");
  write_colmap_text(tmp + "/pts/sparse/0", m);
}

// The option values a run could not use: refused before any work, naming the flag or the key
// (docs/methods.md and docs/reconstruction.md, "Options that cannot take effect").
void unread_options(std::vector<Case>& c) {
  auto json = [](const std::string& name, const std::string& body) {
    return [name, body](const std::string& t) { text(t + "/" + name, body); };
  };
  const std::string scenes = std::string(WEATHERGS_SOURCE_DIR) + "/scenes";
  const std::string tr = "train --data $D --iterations 20 ";
  c.push_back({"unread: train --full-resolution-at at full resolution", {}, tr + "--full-resolution-at 0.3 --out $T/unread",
               "--full-resolution-at", "unread"});
  c.push_back({"unread: train --distractor-opacity-weight without distractors", {},
               tr + "--distractor-opacity-weight 0.5 --out $T/unread", "--distractor-opacity-weight", "unread"});
  c.push_back({"unread: train --mask-normalization without masks", {}, tr + "--mask-normalization reference --out $T/unread",
               "--mask-normalization", "unread"});
  c.push_back({"unread: train --random-init from SfM points", with_points,
               "train --data $T/pts --iterations 20 --random-init frustum --out $T/unread", "--random-init", "unread"});
  c.push_back({"unread: train --train-options random_init_count from SfM points",
               [json](const std::string& t) { with_points(t), json("o.json", R"({"random_init_count": 100})")(t); },
               "train --data $T/pts --iterations 20 --train-options $T/o.json --out $T/unread", "o.json:/random_init_count", "unread"});
  c.push_back({"unread: train --large-prune-from after the last densification", {},
               tr + "--large-prune-from 5000 --out $T/unread", "--large-prune-from", "unread"});
  c.push_back({"unread: train --large-prune without a densification step after the prune's start", {},
               tr + "--large-prune camera_extent --large-prune-from 19 --out $T/unread", "--large-prune", "unread"});
  c.push_back({"unread: train densify_from past the run", json("o.json", R"({"densify_from": 900})"),
               tr + "--train-options $T/o.json --out $T/unread", "densify_from", "unread"});
  c.push_back({"unread: train max_screen_size_px (inert)", json("o.json", R"({"max_screen_size_px": 10})"),
               tr + "--train-options $T/o.json --out $T/unread", "max_screen_size_px", "unread"});
  c.push_back({"unread: train visibility_weight without --in-the-wild", json("o.json", R"({"visibility_weight": 0.5})"),
               tr + "--train-options $T/o.json --out $T/unread", "visibility_weight", "unread"});
  c.push_back({"unread: train in_the_wild_from past the run", json("o.json", R"({"in_the_wild_from": 500})"),
               tr + "--in-the-wild --train-options $T/o.json --out $T/unread", "in_the_wild_from", "unread"});
  c.push_back({"unread: train blend_prune_threshold without blend_prune_at", json("o.json", R"({"blend_prune_threshold": 0.02})"),
               tr + "--train-options $T/o.json --out $T/unread", "blend_prune_threshold", "unread"});
  c.push_back({"unread: train blend_prune_at past the run", json("o.json", R"({"blend_prune_at": [10, 50]})"),
               tr + "--train-options $T/o.json --out $T/unread", "blend_prune_at", "unread"});
  c.push_back({"unread: train position_lr_hold_until past the run", json("o.json", R"({"position_lr_hold_until": 50})"),
               tr + "--train-options $T/o.json --out $T/unread", "position_lr_hold_until", "unread"});
  c.push_back({"unread: train --checkpoint-every not below the run", {}, tr + "--checkpoint-every 20 --out $T/unread",
               "--checkpoint-every", "unread"});
  c.push_back({"unread: train --images beside --images-dir", {}, tr + "--images clean --images-dir $D/clean --out $T/unread",
               "--images-dir replaces", "unread"});
  c.push_back({"unread: train --force beside --resume", {}, "train --resume --force --out $T/run", "--force", ""});
  const std::string rc = "reconstruct --data $D --no-lpips --no-triangulate --out $T/unread --method ";
  c.push_back({"unread: reconstruct --eval-at past the run", {}, rc + "3dgs --iterations 50 --eval-at 25,60", "--eval-at", "unread"});
  c.push_back({"unread: reconstruct --eval-at-fractions outside (0, 1]", {}, rc + "3dgs --eval-at-fractions 0.5,1.5",
               "--eval-at-fractions", "unread"});
  c.push_back({"unread: reconstruct --checkpoint-every not below the run", {}, rc + "3dgs --iterations 50 --checkpoint-every 60",
               "--checkpoint-every", "unread"});
  c.push_back({"unread: reconstruct --nerf-iterations on 3DGS", {}, rc + "3dgs --nerf-iterations 100", "--nerf-iterations", "unread"});
  c.push_back({"unread: reconstruct --nerf-options on 3DGS", json("n.json", "{}"), rc + "oracle --nerf-options $T/n.json",
               "--nerf-options", "unread"});
  c.push_back({"unread: reconstruct a 3DGS flag on a radiance field", {}, rc + "nerf --max-gaussians 1000", "--max-gaussians", "unread"});
  c.push_back({"unread: reconstruct --checkpoint-every not below a radiance field's run", {},
               rc + "nerf --nerf-iterations 50 --checkpoint-every 50", "--checkpoint-every", "unread"});
  c.push_back({"unread: reconstruct --iterations on a radiance field without --eval-at", {}, rc + "nerf --iterations 100",
               "--iterations", "unread"});
  c.push_back({"unread: reconstruct --led-weights without the LED", {}, rc + "3dgs --led-weights $T/led", "--led-weights", "unread"});
  c.push_back({"unread: reconstruct --led-threshold without the LED", {}, rc + "aef-tophat --led-threshold 0.5",
               "--led-threshold", "unread"});
  c.push_back({"unread: reconstruct --led-threshold 0", {}, rc + "weathergs-no-aef --led-threshold 0", "--led-threshold", "unread"});
  c.push_back({"unread: reconstruct --led-adapt on per-view maps", {}, rc + "derainnerf --led-adapt", "--led-adapt", "unread"});
  c.push_back({"unread: reconstruct --aef-weights without the learned AEF", {}, rc + "aef-tophat --aef-weights $T/aef",
               "--aef-weights", "unread"});
  c.push_back({"unread: reconstruct --colmap with --no-triangulate", {}, rc + "3dgs --colmap /bin/true", "--colmap", "unread"});
  c.push_back({"unread: reconstruct --colmap with the dataset's points", with_points,
               "reconstruct --data $T/pts --no-lpips --out $T/unread --method 3dgs --colmap /bin/true", "--colmap", "unread"});
  c.push_back({"unread: reconstruct --random-init with the dataset's points", with_points,
               "reconstruct --data $T/pts --no-lpips --out $T/unread --method 3dgs --random-init frustum", "--random-init", "unread"});
  c.push_back({"unread: reconstruct --lpips-model with --no-lpips", {}, rc + "3dgs --lpips-model $T/lpips", "--lpips-model", "unread"});
  c.push_back({"unread: reconstruct --mask-normalization without loss masks", {}, rc + "3dgs --mask-normalization reference",
               "--mask-normalization", "unread"});
  c.push_back({"unread: reconstruct --distractor-opacity-weight off desplat", {}, rc + "3dgs --distractor-opacity-weight 0.5",
               "--distractor-opacity-weight", "unread"});
  c.push_back({"unread: reconstruct --downsample-start on gs-w-lite", {}, rc + "gs-w-lite --downsample-start 2",
               "downsample_start", "unread"});
  c.push_back({"unread: reconstruct a recipe's key in --train-options", json("o.json", R"({"in_the_wild": true})"),
               rc + "3dgs --train-options $T/o.json", "o.json:/in_the_wild", "unread"});
  c.push_back({"unread: reconstruct seed in --nerf-options", json("n.json", R"({"seed": 3})"), rc + "nerf --nerf-options $T/n.json",
               "n.json:/seed", "unread"});
  c.push_back({"unread: reconstruct upsample_at past the run in --nerf-options",
               json("n.json", R"({"iterations": 80, "level_scales": [0.5, 1.0], "upsample_at": [100]})"),
               rc + "nerf --nerf-options $T/n.json", "n.json:/upsample_at", "unread"});
  c.push_back({"unread: reconstruct tv_fraction with TV off in --nerf-options",
               json("n.json", R"({"tv_density": 0, "tv_color": 0, "tv_fraction": 0.1})"), rc + "nerf --nerf-options $T/n.json",
               "n.json:/tv_fraction", "unread"});
  const std::string gen = "generate --scene " + scenes + "/pool.json --profile tiny --cache $T/c --out $T/g ";
  c.push_back({"unread: generate --max-views not below the views", {}, gen + "--weather rain --max-views 5", "--max-views", "g"});
  c.push_back({"unread: generate --seed on a clear variant", {}, gen + "--weather clear --seed 3", "--seed", "g"});
  c.push_back({"unread: generate --targets on a clear variant", {}, gen + "--weather clear --targets", "--targets", "g"});
  c.push_back({"unread: generate --colmap with --no-colmap", {}, gen + "--weather rain --no-colmap --colmap /bin/true",
               "--colmap", "g"});
  c.push_back({"unread: generate a negative --seed", {}, gen + "--weather rain --seed -4", "--seed", "g"});
}

std::vector<Case> corpus() {
  const std::string img_a = std::string(WEATHERGS_TEST_DATA_DIR) + "/ssim/blur_a.png";
  auto spec = [](const std::string& body) {
    return [body](const std::string& t) { text(t + "/spec.json", body); };
  };
  std::vector<Case> c;
  // compare
  c.push_back({"compare: missing file", {}, "compare $T/none.png " + img_a + " --no-lpips", "$T/none.png", ""});
  c.push_back({"compare: text as png", [](const std::string& t) { text(t + "/text.png", "not an image"); },
               "compare $T/text.png " + img_a + " --no-lpips", "text.png", ""});
  c.push_back({"compare: truncated png",
               [img_a](const std::string& t) { text(t + "/trunc.png", read_file(img_a).substr(0, 60)); },
               "compare $T/trunc.png " + img_a + " --no-lpips", "trunc.png", ""});
  c.push_back({"compare: empty file", [](const std::string& t) { text(t + "/empty.png", ""); },
               "compare $T/empty.png " + img_a + " --no-lpips", "empty.png", ""});
  c.push_back({"compare: size mismatch",
               [](const std::string& t) { write_image(t + "/small.png", Image(8, 8, 3, ColorSpace::kSRGB, 0.5f)); },
               "compare $T/small.png " + img_a + " --no-lpips", "small.png", ""});
  c.push_back({"compare: folder as image", [](const std::string& t) { fs::create_directories(t + "/dir.png"); },
               "compare $T/dir.png " + img_a + " --no-lpips", "dir.png", ""});
  c.push_back({"compare: png header claiming 100000x100000",
               [](const std::string& t) { text(t + "/huge.png", png_header_only(100000, 100000)); },
               "compare $T/huge.png " + img_a + " --no-lpips", "huge.png", ""});
  c.push_back({"compare: png header claiming 0x0", [](const std::string& t) { text(t + "/zero.png", png_header_only(0, 0)); },
               "compare $T/zero.png " + img_a + " --no-lpips", "zero.png", ""});
  c.push_back({"compare: missing lpips model", {}, "compare " + img_a + " " + img_a + " --lpips-model $T/nope.onnx",
               "nope.onnx", ""});
  // evaluate
  c.push_back({"evaluate: missing dataset", {}, "evaluate --gt $T/none --renders $T --method m --no-lpips -o $T/r.json", "$T/none",
               "r.json"});
  c.push_back({"evaluate: malformed dataset.json", [](const std::string& t) {
                 copy_tree(t + "/data", t + "/m");
                 text(t + "/m/dataset.json", "{\"format\": ");
               },
               "evaluate --gt $T/m --renders $T/renders --method m --no-lpips -o $T/r.json", "dataset.json", "r.json"});
  c.push_back({"evaluate: unknown key in dataset.json",
               [](const std::string& t) { patched(t, "u", "dataset.json", [](Json& j) { j["colour"] = 1; }); },
               "evaluate --gt $T/u --renders $T/renders --method m --no-lpips -o $T/r.json", "colour", "r.json"});
  c.push_back({"evaluate: wrong type in cameras.json",
               [](const std::string& t) { patched(t, "wt", "cameras.json", [](Json& j) { j["views"][0]["fx"] = "big"; }); },
               "evaluate --gt $T/wt --renders $T/renders --method m --no-lpips -o $T/r.json", "/views/0/fx", "r.json"});
  c.push_back({"evaluate: negative focal length",
               [](const std::string& t) { patched(t, "n", "cameras.json", [](Json& j) { j["views"][1]["fx"] = -5; }); },
               "evaluate --gt $T/n --renders $T/renders --method m --no-lpips -o $T/r.json", "cameras.json", "r.json"});
  c.push_back({"evaluate: split refers to a missing view",
               [](const std::string& t) {
                 patched(t, "s", "dataset.json", [](Json& j) { j["splits"]["test"].push_back("zzz"); });
               },
               "evaluate --gt $T/s --renders $T/renders --method m --no-lpips -o $T/r.json", "zzz", "r.json"});
  c.push_back({"evaluate: missing render", [](const std::string& t) { fs::remove(t + "/renders/000.png"); },
               "evaluate --gt $D --renders $T/renders --method m --no-lpips -o $T/r.json", "000", "r.json"});
  c.push_back({"evaluate: extra render",
               [](const std::string& t) { write_image(t + "/renders/999.png", Image(96, 64, 3, ColorSpace::kSRGB)); },
               "evaluate --gt $D --renders $T/renders --method m --no-lpips -o $T/r.json", "999", "r.json"});
  c.push_back({"evaluate: corrupt render", [](const std::string& t) { text(t + "/renders/000.png", "\x89PNG garbage"); },
               "evaluate --gt $D --renders $T/renders --method m --no-lpips -o $T/r.json", "000.png", "r.json"});
  c.push_back({"evaluate: render of the wrong size",
               [](const std::string& t) { write_image(t + "/renders/000.png", Image(20, 10, 3, ColorSpace::kSRGB)); },
               "evaluate --gt $D --renders $T/renders --method m --no-lpips -o $T/r.json", "000", "r.json"});
  c.push_back({"evaluate: missing split", {}, "evaluate --gt $D --renders $T/renders --split val --method m --no-lpips -o $T/r.json",
               "val", "r.json"});
  c.push_back({"evaluate: missing mask folder", {},
               "evaluate --gt $D --renders $T/renders --mask-dir $T/nomasks --method m --no-lpips -o $T/r.json", "nomasks", "r.json"});
  c.push_back({"evaluate: unwritable output", {}, "evaluate --gt $D --renders $T/renders --method m --no-lpips -o /dev/null/r.json",
               "/dev/null", ""});
  c.push_back({"evaluate: renders folder missing", {}, "evaluate --gt $D --renders $T/norenders --method m --no-lpips -o $T/r.json",
               "norenders", "r.json"});
  // leaderboard / check
  c.push_back({"leaderboard: malformed results", [](const std::string& t) { text(t + "/bad.json", "[1, 2"); },
               "leaderboard $T/bad.json", "bad.json", ""});
  c.push_back({"leaderboard: wrong format", [](const std::string& t) {
                 Json r = results_json();
                 r["format"] = "something-else";
                 text(t + "/fmt.json", r.dump());
               },
               "leaderboard $T/fmt.json", "fmt.json", ""});
  c.push_back({"leaderboard: unknown key", [](const std::string& t) {
                 Json r = results_json();
                 r["extra"] = 1;
                 text(t + "/uk.json", r.dump());
               },
               "leaderboard $T/uk.json", "extra", ""});
  c.push_back({"leaderboard: wrong version", [](const std::string& t) {
                 Json r = results_json();
                 r["version"] = 99;
                 text(t + "/v.json", r.dump());
               },
               "leaderboard $T/v.json", "v.json", ""});
  c.push_back({"leaderboard: metric of the wrong type", [](const std::string& t) {
                 Json r = results_json();
                 r["metrics"]["psnr"] = "high";
                 text(t + "/wt.json", r.dump());
               },
               "leaderboard $T/wt.json", "psnr", ""});
  c.push_back({"leaderboard: html to an unwritable path", [](const std::string& t) { text(t + "/ok.json", results_json().dump()); },
               "leaderboard $T/ok.json --format html -o /dev/null/lb.html", "/dev/null", ""});
  c.push_back({"leaderboard: missing file", {}, "leaderboard $T/missing.json", "missing.json", ""});
  c.push_back({"leaderboard: unknown table format", [](const std::string& t) { text(t + "/ok.json", results_json().dump()); },
               "leaderboard $T/ok.json --format docx", "docx", ""});
  c.push_back({"leaderboard: unwritable output", [](const std::string& t) { text(t + "/ok.json", results_json().dump()); },
               "leaderboard $T/ok.json -o /dev/null/table.md", "/dev/null", ""});
  c.push_back({"check: missing baseline", [](const std::string& t) { text(t + "/ok.json", results_json().dump()); },
               "check --baseline $T/nobase.json --results $T/ok.json", "nobase.json", ""});
  c.push_back({"check: negative tolerance", [](const std::string& t) { text(t + "/ok.json", results_json().dump()); },
               "check --baseline $T/ok.json --results $T/ok.json --psnr-tol -1", "psnr", ""});
  c.push_back({"check: NaN metric", [](const std::string& t) {
                 std::string s = results_json().dump();
                 s.replace(s.find("20.0"), 4, "NaN");
                 text(t + "/nan.json", s);
               },
               "check --baseline $T/nan.json --results $T/nan.json", "nan.json", ""});
  // example
  c.push_back({"example: unwritable output", {}, "example -o /dev/null/ex", "/dev/null", ""});
  c.push_back({"example: zero-size images", {}, "example -o $T/ex --width 0", "width", "ex"});
  // weather
  c.push_back({"weather: malformed spec", spec("{\"effects\": "), "weather --in $D --spec $T/spec.json --out $T/w",
               "spec.json", "w"});
  c.push_back({"weather: unknown key", spec(R"({"effects": {"rain": {"rate_mm_h": 5, "colour": 1}}})"),
               "weather --in $D --spec $T/spec.json --out $T/w", "colour", "w"});
  c.push_back({"weather: unknown effect", spec(R"({"effects": {"hail": {"rate_mm_h": 5}}})"),
               "weather --in $D --spec $T/spec.json --out $T/w", "hail", "w"});
  c.push_back({"weather: negative rate", spec(R"({"effects": {"rain": {"rate_mm_h": -5}}})"),
               "weather --in $D --spec $T/spec.json --out $T/w", "rate_mm_h", "w"});
  c.push_back({"weather: absurd rate", spec(R"({"effects": {"snow": {"rate_mm_h": 1e9}}})"),
               "weather --in $D --spec $T/spec.json --out $T/w", "rate_mm_h", "w"});
  c.push_back({"weather: wrong type", spec(R"({"effects": {"rain": {"rate_mm_h": "lots"}}})"),
               "weather --in $D --spec $T/spec.json --out $T/w", "/effects/rain/rate_mm_h", "w"});
  c.push_back({"weather: bad wind array", spec(R"({"effects": {"rain": {"rate_mm_h": 5, "wind_m_s": [1, 2]}}})"),
               "weather --in $D --spec $T/spec.json --out $T/w", "wind_m_s", "w"});
  c.push_back({"weather: unknown intensity", spec(R"({"effects": {"rain": {"intensity": "biblical"}}})"),
               "weather --in $D --spec $T/spec.json --out $T/w", "intensity", "w"});
  c.push_back({"weather: paper block in a physical spec", spec(R"({"effects": {"rain": {"rate_mm_h": 5, "paper": {}}}})"),
               "weather --in $D --spec $T/spec.json --out $T/w", "paper", "w"});
  c.push_back({"weather: 10^9 lens drops", spec(R"({"effects": {"lens_droplets": {"count": 1000000000}}})"),
               "weather --in $D --spec $T/spec.json --out $T/w", "count", "w"});
  c.push_back({"weather: negative f-number", spec(R"({"camera": {"f_number": -2}, "effects": {"rain": {"rate_mm_h": 5}}})"),
               "weather --in $D --spec $T/spec.json --out $T/w", "f_number", "w"});
  c.push_back({"weather: negative seed", spec(R"({"seed": -1, "effects": {"rain": {"rate_mm_h": 5}}})"),
               "weather --in $D --spec $T/spec.json --out $T/w", "seed", "w"});
  c.push_back({"weather: missing depth", [](const std::string& t) {
                 text(t + "/spec.json", R"({"effects": {"rain": {"rate_mm_h": 5}}})");
                 copy_tree(t + "/data", t + "/nd");
                 fs::remove(t + "/nd/depth/001.exr");
               },
               "weather --in $T/nd --spec $T/spec.json --out $T/w", "001", "w"});
  c.push_back({"weather: NaN depth", [](const std::string& t) {
                 text(t + "/spec.json", R"({"effects": {"rain": {"rate_mm_h": 5}}})");
                 copy_tree(t + "/data", t + "/nan");
                 Image d = read_depth(t + "/nan/depth/002.exr");
                 d.data[5] = std::numeric_limits<float>::quiet_NaN();
                 write_depth(t + "/nan/depth/002.exr", d);
               },
               "weather --in $T/nan --spec $T/spec.json --out $T/w", "002.exr", "w"});
  c.push_back({"weather: negative depth", [](const std::string& t) {
                 text(t + "/spec.json", R"({"effects": {"fog": {"visibility_m": 50}}})");
                 copy_tree(t + "/data", t + "/neg");
                 Image d = read_depth(t + "/neg/depth/003.exr");
                 for (float& z : d.data) z = -z;
                 write_depth(t + "/neg/depth/003.exr", d);
               },
               "weather --in $T/neg --spec $T/spec.json --out $T/w", "003.exr", "w"});
  c.push_back({"weather: -inf depth", [](const std::string& t) {
                 text(t + "/spec.json", R"({"effects": {"rain": {"rate_mm_h": 5}}})");
                 copy_tree(t + "/data", t + "/ninf");
                 Image d = read_depth(t + "/ninf/depth/004.exr");
                 d.data[7] = -std::numeric_limits<float>::infinity();
                 write_depth(t + "/ninf/depth/004.exr", d);
               },
               "weather --in $T/ninf --spec $T/spec.json --out $T/w", "004.exr", "w"});
  c.push_back({"weather: truncated depth EXR", [](const std::string& t) {
                 text(t + "/spec.json", R"({"effects": {"rain": {"rate_mm_h": 5}}})");
                 copy_tree(t + "/data", t + "/trx");
                 text(t + "/trx/depth/005.exr", read_file(t + "/trx/depth/005.exr").substr(0, 100));
               },
               "weather --in $T/trx --spec $T/spec.json --out $T/w", "005.exr", "w"});
  c.push_back({"weather: text as depth EXR", [](const std::string& t) {
                 text(t + "/spec.json", R"({"effects": {"rain": {"rate_mm_h": 5}}})");
                 copy_tree(t + "/data", t + "/txx");
                 text(t + "/txx/depth/006.exr", "not an exr");
               },
               "weather --in $T/txx --spec $T/spec.json --out $T/w", "006.exr", "w"});
  c.push_back({"weather: 8-bit PNG bytes as depth EXR", [img_a](const std::string& t) {
                 text(t + "/spec.json", R"({"effects": {"rain": {"rate_mm_h": 5}}})");
                 copy_tree(t + "/data", t + "/pngx");
                 text(t + "/pngx/depth/007.exr", read_file(img_a));
               },
               "weather --in $T/pngx --spec $T/spec.json --out $T/w", "007.exr", "w"});
  c.push_back({"weather: zero fog visibility", spec(R"({"effects": {"fog": {"visibility_m": 0}}})"),
               "weather --in $D --spec $T/spec.json --out $T/w", "visibility_m", "w"});
  c.push_back({"weather: number beyond double", spec(R"({"effects": {"fog": {"visibility_m": 1e400}}})"),
               "weather --in $D --spec $T/spec.json --out $T/w", "spec.json", "w"});
  c.push_back({"weather: image size mismatch", [](const std::string& t) {
                 text(t + "/spec.json", R"({"effects": {"rain": {"rate_mm_h": 5}}})");
                 copy_tree(t + "/data", t + "/sz");
                 write_image(t + "/sz/clean/000.png", Image(10, 10, 3, ColorSpace::kSRGB));
               },
               "weather --in $T/sz --spec $T/spec.json --out $T/w", "000", "w"});
  c.push_back({"weather: unwritable output", spec(R"({"effects": {"rain": {"rate_mm_h": 5}}})"),
               "weather --in $D --spec $T/spec.json --out /dev/null/w", "/dev/null", ""});
  c.push_back({"weather: missing spec", {}, "weather --in $D --spec $T/nospec.json --out $T/w", "nospec.json", "w"});
  // generate and import (fail before any rendering)
  const std::string scenes = std::string(WEATHERGS_SOURCE_DIR) + "/scenes";
  c.push_back({"generate: missing scene", {}, "generate --scene $T/none.json --weather rain --cache $T/c --out $T/g",
               "none.json", "g"});
  c.push_back({"generate: unknown variant", {}, "generate --scene " + scenes + "/pool.json --weather hail --cache $T/c --out $T/g",
               "hail", "g"});
  c.push_back({"generate: unknown profile", {},
               "generate --scene " + scenes + "/pool.json --weather rain --profile huge --cache $T/c --out $T/g", "huge", "g"});
  c.push_back({"generate: unknown key in scene", [scenes](const std::string& t) {
                 Json j = read_json_file(scenes + "/pool.json");
                 j["colour"] = 1;
                 text(t + "/scene.json", j.dump());
               },
               "generate --scene $T/scene.json --weather rain --cache $T/c --out $T/g", "colour", "g"});
  c.push_back({"generate: 0x0 profile", [scenes](const std::string& t) {
                 Json j = read_json_file(scenes + "/pool.json");
                 j["profiles"]["tiny"]["width"] = 0;
                 text(t + "/scene.json", j.dump());
               },
               "generate --scene $T/scene.json --weather rain --profile tiny --cache $T/c --out $T/g", "width", "g"});
  c.push_back({"generate: malformed suite", [](const std::string& t) { text(t + "/suite.json", "{\"name\": 3}"); },
               "generate --suite $T/suite.json --cache $T/c --out $T/g", "suite.json", ""});
  c.push_back({"generate: unwritable output", {},
               "generate --scene " + scenes + "/pool.json --weather rain --cache $T/c --out /dev/null/g", "/dev/null", ""});
  c.push_back({"import: missing video", {}, "import --video $T/none.mp4 --out $T/i", "none.mp4", "i"});
  c.push_back({"import: not a video", [](const std::string& t) { text(t + "/v.mp4", "text"); },
               "import --video $T/v.mp4 --out $T/i", "v.mp4", "i"});
  c.push_back({"import: every 0", [](const std::string& t) { text(t + "/v.mp4", "text"); },
               "import --video $T/v.mp4 --every 0 --out $T/i", "every", "i"});
  // train
  c.push_back({"train: missing dataset", {}, "train --data $T/none --out $T/run2", "$T/none", "run2"});
  c.push_back({"train: no lens masks in the dataset", {}, "train --data $D --masks lens --out $T/run2", "masks/lens", "run2"});
  c.push_back({"train: mask of the wrong size", [](const std::string& t) {
                 fs::create_directories(t + "/mk");
                 for (const char* v : {"001", "002", "003", "004", "005", "006", "007"})
                   write_mask(t + "/mk/" + v + ".png", Image(4, 4, 1, ColorSpace::kLinear));
               },
               "train --data $D --masks-dir $T/mk --out $T/run2", "mk/", "run2"});
  c.push_back({"train: missing image folder", {}, "train --data $D --images-dir $T/noimg --out $T/run2", "noimg", "run2"});
  c.push_back({"train: truncated training image", [](const std::string& t) {
                 copy_tree(t + "/data", t + "/tri");
                 text(t + "/tri/images/003.png", read_file(t + "/tri/images/003.png").substr(0, 80));
               },
               "train --data $T/tri --iterations 2 --out $T/run2", "003.png", "run2"});
  c.push_back({"train: training image of the wrong size", [](const std::string& t) {
                 copy_tree(t + "/data", t + "/wsi");
                 write_image(t + "/wsi/images/004.png", Image(12, 8, 3, ColorSpace::kSRGB));
               },
               "train --data $T/wsi --iterations 2 --out $T/run2", "004", "run2"});
  c.push_back({"train: zero iterations", {}, "train --data $D --iterations 0 --out $T/run2", "iterations", "run2"});
  c.push_back({"train: negative random init count", {}, "train --data $D --random-init-count -5 --out $T/run2",
               "random_init_count", "run2"});
  c.push_back({"train: unwritable output", {}, "train --data $D --iterations 2 --out /dev/null/run", "/dev/null", ""});
  c.push_back({"train: resume a run from another version", [](const std::string& t) {
                 copy_tree(t + "/run", t + "/oldrun");
                 Json j = read_json_file(t + "/oldrun/run.json");
                 j["version"] = 1;
                 write_file_atomic(t + "/oldrun/run.json", j.dump());
               },
               "train --resume --out $T/oldrun", "version", ""});
  c.push_back({"train: resume a corrupt checkpoint", [](const std::string& t) {
                 copy_tree(t + "/run", t + "/badck");
                 write_file_atomic(t + "/badck/checkpoint.bin", "garbage");
               },
               "train --resume --out $T/badck", "checkpoint.bin", ""});
  // render
  c.push_back({"render: truncated PLY", [](const std::string& t) {
                 copy_tree(t + "/run", t + "/trply");
                 const std::string ply = read_file(t + "/trply/point_cloud.ply");
                 write_file_atomic(t + "/trply/point_cloud.ply", ply.substr(0, ply.size() - 7));
               },
               "render --model $T/trply --out $T/rr", "point_cloud.ply", "rr"});
  c.push_back({"render: missing model", {}, "render --model $T/nomodel --out $T/rr", "nomodel", "rr"});
  c.push_back({"render: run from another version", [](const std::string& t) {
                 copy_tree(t + "/run", t + "/oldrun2");
                 Json j = read_json_file(t + "/oldrun2/run.json");
                 j["version"] = 1;
                 write_file_atomic(t + "/oldrun2/run.json", j.dump());
               },
               "render --model $T/oldrun2 --out $T/rr", "version", "rr"});
  c.push_back({"render: corrupt PLY", [](const std::string& t) {
                 copy_tree(t + "/run", t + "/badply");
                 write_file_atomic(t + "/badply/point_cloud.ply", "ply\nformat ascii 1.0\nend_header\n");
               },
               "render --model $T/badply --out $T/rr", "point_cloud.ply", "rr"});
  c.push_back({"render: unknown split", {}, "render --model $T/run --split nope --out $T/rr", "nope", "rr"});
  c.push_back({"render: unwritable output", {}, "render --model $T/run --out /dev/null/rr", "/dev/null", ""});
  c.push_back({"render: depth opacity out of range", {}, "render --model $T/run --depth --depth-min-opacity 0 --out $T/rr",
               "depth_min_opacity", "rr"});
  // usage
  c.push_back({"usage: unknown command", {}, "frobnicate", "frobnicate", ""});
  c.push_back({"usage: unknown flag", {}, "train --data $D --out $T/run2 --bogus", "bogus", "run2"});
  // the LED adaptation's length and layouts need the adaptation; a length it cannot run is named
  c.push_back({"usage: detect --adapt-passes without --adapt", {}, "detect --data $D --out $T/ledmasks --adapt-passes 5",
               "--adapt-passes requires --adapt", "ledmasks"});
  c.push_back({"usage: reconstruct --led-adapt-layouts without --led-adapt", {},
               "reconstruct --data $D --method weathergs-no-aef --out $T/ledrun --led-adapt-layouts 1",
               "--led-adapt-layouts requires --led-adapt", "ledrun"});
  c.push_back({"detect: zero adaptation passes", {}, "detect --data $D --out $T/ledmasks --adapt --adapt-passes 0", "passes", "ledmasks"});
  unread_options(c);
  return c;
}

TEST(BadInputCorpus, EveryCaseExitsTwoNamesTheProblemAndLeavesNothing) {
  testing::TempDir tmp;
  testing::SceneOptions so;
  so.views = 9;
  testing::make_clean_dataset(tmp / "data", so);
  // images/ = clean/ so the dataset also trains; a tiny trained run for the resume/render cases.
  copy_tree(tmp / "data/clean", tmp / "data/images");
  ASSERT_EQ(run("train --data " + (tmp / "data") + " --iterations 3 --random-init-count 50 --out " + (tmp / "run"),
                tmp / "setup.log"),
            0)
      << read_file(tmp / "setup.log");
  const std::vector<Case> cases = corpus();
  EXPECT_GE(cases.size(), 60u);
  int index = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    // Fresh renders for the evaluate cases (some cases edit them).
    fs::remove_all(tmp / "renders");
    copy_tree(tmp / "data/clean", tmp / "renders");
    for (const auto& e : fs::directory_iterator(tmp / "renders"))
      if (e.path().stem() == "001" || e.path().stem() == "002" || e.path().stem() == "003" ||
          e.path().stem() == "004" || e.path().stem() == "005" || e.path().stem() == "006" || e.path().stem() == "007")
        fs::remove(e.path());
    if (c.setup) c.setup(tmp.path());
    const std::string log = tmp / ("case" + std::to_string(index++) + ".log");
    const int code = run(expand(c.args, tmp.path()), log);
    const std::string out = read_file(log);
    EXPECT_EQ(code, 2) << out;
    EXPECT_NE(out.find(expand(c.message, tmp.path())), std::string::npos) << "message: " << out;
    if (!c.output.empty()) {
      EXPECT_FALSE(fs::exists(tmp / c.output)) << c.output;
      // No temporary sibling left behind either.
      for (const auto& e : fs::directory_iterator(tmp.path()))
        EXPECT_EQ(e.path().filename().string().find(c.output + ".tmp-"), std::string::npos) << e.path();
    }
  }
}

}  // namespace
}  // namespace weathergs
