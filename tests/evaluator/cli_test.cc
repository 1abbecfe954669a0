// End-to-end tests of the evaluator commands through the `weathergs` binary: exit codes, messages,
// and that failed runs leave no output behind.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset_identity.h"
#include "core/image.h"
#include "core/json_reader.h"
#include "tests/core/test_util.h"

namespace weathergs {
namespace {

namespace fs = std::filesystem;
using testing::run_command;
using testing::TempDir;

const std::string kBin = WEATHERGS_BINARY;

// One example benchmark shared by the tests of this file (written once, read-only afterwards).
class EvaluatorCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new TempDir();
    auto r = run_command(kBin + " --quiet example -o " + ex());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() { delete root_; }
  static std::string ex() { return *root_ / "ex"; }
  static std::string ds(const std::string& name = "park_rain") { return ex() + "/datasets/" + name; }
  static std::string renders(const std::string& m, const std::string& name = "park_rain") {
    return ex() + "/renders/" + m + "/" + name;
  }
  static TempDir* root_;
};
TempDir* EvaluatorCli::root_ = nullptr;

TEST_F(EvaluatorCli, EvaluateWritesTheResultsFormat) {
  TempDir out;
  auto r = run_command(kBin + " --quiet evaluate --gt " + ds() + " --renders " + renders("box-blur") +
                       " -o " + (out / "r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  Json j = read_json_file(out / "r.json");
  EXPECT_EQ(j["format"], "weathergs-results");
  EXPECT_EQ(j["method"], "box-blur");  // from info.json
  EXPECT_EQ(j["dataset"], "park_rain");
  EXPECT_EQ(j["protocol"]["ssim"], "gaussian11_sigma1.5_valid");
  EXPECT_EQ(j["protocol"]["lpips"], "alex_v0.1");
  EXPECT_EQ(j["protocol"]["quantize_uint8"], true);
  EXPECT_EQ(j["per_view"].size(), 2u);  // views 000 and 008 of 9
  EXPECT_EQ(j["sha256"]["renders"].get<std::string>().size(), 64u);
  EXPECT_GT(j["metrics"]["psnr"].get<double>(), 20);
  EXPECT_EQ(j["method_info"]["method"], "box-blur");
  // Same inputs -> byte-identical results, whatever the thread count.
  auto r1 = run_command(kBin + " --quiet -j 1 evaluate --gt " + ds() + " --renders " + renders("box-blur") +
                        " -o " + (out / "r1.json"));
  ASSERT_EQ(r1.exit_code, 0) << r1.output;
  EXPECT_EQ(read_file(out / "r.json"), read_file(out / "r1.json"));
}

TEST_F(EvaluatorCli, CompareJsonAndIdenticalImages) {
  const std::string gt = ds() + "/clean/000.png";
  auto r = run_command(kBin + " compare --json " + gt + " " + gt);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  Json j = Json::parse(r.output);
  EXPECT_TRUE(j["psnr"].is_null());
  EXPECT_EQ(j["psnr_infinite"], true);
  EXPECT_EQ(j["ssim"], 1.0);
  EXPECT_EQ(j["lpips"], 0.0);
  auto t = run_command(kBin + " compare " + gt + " " + gt);
  EXPECT_NE(t.output.find("+inf"), std::string::npos) << t.output;
}

// Copies a render folder so a test can break it.
std::string copy_renders(const std::string& from, const TempDir& dir) {
  const std::string to = dir / "renders";
  fs::copy(from, to, fs::copy_options::recursive);
  return to;
}

void expect_bad_input(const std::string& command, const std::string& must_mention, const std::string& no_file) {
  auto r = run_command(command);
  EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.output;
  EXPECT_NE(r.output.find(must_mention), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(no_file)) << "a failed run left " << no_file;
}

TEST_F(EvaluatorCli, BadRendersAreClearErrorsAndLeaveNoResults) {
  TempDir dir;
  const std::string out = dir / "results.json";
  const std::string eval = kBin + " --quiet evaluate --gt " + ds() + " -o " + out + " --renders ";
  {  // corrupt PNG
    TempDir d;
    std::string rd = copy_renders(renders("noise"), d);
    write_file_atomic(rd + "/008.png", "garbage, not a png");
    expect_bad_input(eval + rd, "008.png", out);
  }
  {  // truncated PNG
    TempDir d;
    std::string rd = copy_renders(renders("noise"), d);
    std::string bytes = read_file(rd + "/000.png");
    write_file_atomic(rd + "/000.png", bytes.substr(0, bytes.size() / 3));
    expect_bad_input(eval + rd, "000.png", out);
  }
  {  // missing view
    TempDir d;
    std::string rd = copy_renders(renders("noise"), d);
    fs::remove(rd + "/008.png");
    expect_bad_input(eval + rd, "missing renders for test view(s): 008", out);
  }
  {  // extra view
    TempDir d;
    std::string rd = copy_renders(renders("noise"), d);
    fs::copy_file(rd + "/000.png", rd + "/003.png");
    expect_bad_input(eval + rd, "not in the test split: 003", out);
  }
  {  // size mismatch
    TempDir d;
    std::string rd = copy_renders(renders("noise"), d);
    write_image(rd + "/000.png", Image(50, 40, 3, ColorSpace::kSRGB, 0.5f));
    expect_bad_input(eval + rd, "view '000'", out);
  }
  {  // malformed info.json
    TempDir d;
    std::string rd = copy_renders(renders("noise"), d);
    write_file_atomic(rd + "/info.json", "{\"method\": ");
    expect_bad_input(eval + rd, "info.json", out);
  }
  // Missing file for compare; missing dataset; bad flag value; unknown subcommand.
  expect_bad_input(kBin + " compare /nonexistent/a.png /nonexistent/b.png", "does not exist", out);
  expect_bad_input(kBin + " evaluate --gt /nonexistent --renders x -o " + out, "/nonexistent", out);
  expect_bad_input(kBin + " evaluate --gt " + ds() + " --renders " + renders("noise") + " -o " + out +
                       " --ssim-padding reflect", "reflect", out);
  expect_bad_input(kBin + " frobnicate", "frobnicate", out);
  // An LPIPS model that cannot be found names the path and how to skip it.
  expect_bad_input(eval + renders("noise") + " --lpips-model /nonexistent/model.onnx", "/nonexistent/model.onnx", out);
  EXPECT_EQ(testing::count_entries(dir.path()), 0);
}

TEST_F(EvaluatorCli, BrokenGroundTruthDatasetIsBadInput) {
  TempDir dir;
  const std::string gt = dir / "gt";
  fs::copy(ds(), gt, fs::copy_options::recursive);
  const std::string out = dir / "r.json";
  const std::string eval = kBin + " --quiet evaluate --no-lpips --gt " + gt + " --renders " + renders("noise") + " -o " + out;
  Json j = read_json_file(gt + "/dataset.json");
  j["splits"]["test"].push_back("999");  // a view cameras.json does not have
  write_file_atomic(gt + "/dataset.json", j.dump());
  expect_bad_input(eval, "'999' is not in cameras.json", out);
  j = read_json_file(ds() + "/dataset.json");
  j["weathr"] = "rain";
  write_file_atomic(gt + "/dataset.json", j.dump());
  expect_bad_input(eval, "'weathr'", out);
  write_file_atomic(gt + "/dataset.json", "{\"format\": \"weathergs-dataset\",");
  expect_bad_input(eval, "malformed JSON", out);
  write_file_atomic(gt + "/dataset.json", read_file(ds() + "/dataset.json"));
  fs::remove_all(gt + "/clean");
  expect_bad_input(eval, "no clean/ folder", out);
  EXPECT_EQ(testing::count_entries(dir.path()), 1);  // only gt/
}

TEST_F(EvaluatorCli, NoLpipsIsRecorded) {
  TempDir out;
  auto r = run_command(kBin + " --quiet evaluate --no-lpips --ssim-padding same --gt " + ds() + " --renders " +
                       renders("shift") + " -o " + (out / "r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  Json j = read_json_file(out / "r.json");
  EXPECT_TRUE(j["protocol"]["lpips"].is_null());
  EXPECT_TRUE(j["metrics"]["lpips"].is_null());
  EXPECT_EQ(j["protocol"]["ssim"], "gaussian11_sigma1.5_same");
}

TEST_F(EvaluatorCli, MaskedEvaluation) {
  TempDir dir;
  // Renders equal to the truth except for a black left half, and masks (255 = exclude) over that left
  // half: the masked scores see a perfect render, the unmasked ones the damage. The reverse mask
  // (the polarity inverted) sees only the damage.
  fs::create_directories(dir / "renders");
  fs::create_directories(dir / "masks");
  fs::create_directories(dir / "inverse");
  for (const char* v : {"000", "008"}) {
    Image gt = read_image(ds() + "/clean/" + v + ".png");
    Image m(gt.width, gt.height, 1, ColorSpace::kLinear, 0.f), inv(gt.width, gt.height, 1, ColorSpace::kLinear, 1.f);
    for (int y = 0; y < gt.height; ++y)
      for (int x = 0; x < gt.width / 2; ++x) {
        for (int c = 0; c < gt.channels; ++c) gt.at(x, y, c) = 0.f;
        m.at(x, y) = 1.f;
        inv.at(x, y) = 0.f;
      }
    write_image(dir / (std::string("renders/") + v + ".png"), gt);
    write_mask(dir / (std::string("masks/") + v + ".png"), m);
    write_mask(dir / (std::string("inverse/") + v + ".png"), inv);
  }
  auto score = [&](const std::string& mask, const std::string& out) {
    auto r = run_command(kBin + " --quiet evaluate --method half --gt " + ds() + " --renders " + (dir / "renders") +
                         (mask.empty() ? "" : " --mask-dir " + (dir / mask)) + " -o " + (dir / out));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return read_json_file(dir / out);
  };
  const Json j = score("masks", "r.json"), whole = score("", "whole.json"), inverse = score("inverse", "inv.json");
  EXPECT_EQ(j["protocol"]["mask"], "masks");
  EXPECT_EQ(j["protocol"]["lpips_mask"], "truth_filled");
  EXPECT_FALSE(whole["protocol"].contains("lpips_mask"));
  // Masked: the valid pixels are identical, so PSNR is infinite, SSIM ~1 and LPIPS 0.
  EXPECT_EQ(j["metrics"]["psnr_infinite"], true) << j.dump();
  EXPECT_GT(j["metrics"]["ssim"].get<double>(), 0.9);  // windows at the edge of the mask still see black
  EXPECT_LT(j["metrics"]["lpips"].get<double>(), 1e-6);
  // Unmasked: half the image is black.
  EXPECT_LT(whole["metrics"]["psnr"].get<double>(), 15.0) << whole.dump();
  EXPECT_GT(whole["metrics"]["lpips"].get<double>(), 0.2);
  // Inverted polarity: only the black half counts, which is worse than the whole image.
  EXPECT_LT(inverse["metrics"]["psnr"].get<double>(), whole["metrics"]["psnr"].get<double>());
  // A missing mask is an error naming it.
  fs::remove(dir / "masks/008.png");
  auto bad = run_command(kBin + " --quiet evaluate --gt " + ds() + " --renders " + renders("noise") + " --mask-dir " +
                         (dir / "masks") + " -o " + (dir / "r2.json"));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("008.png"), std::string::npos) << bad.output;
}

TEST_F(EvaluatorCli, LeaderboardAndCheckRoundTrip) {
  TempDir dir;
  std::vector<std::string> files;
  for (const char* m : {"box-blur", "noise", "shift"})
    for (const char* d : {"park_rain", "yard_rain", "park_snow"}) {
      std::string f = dir / (std::string(m) + "_" + d + ".json");
      auto r = run_command(kBin + " --quiet evaluate --no-lpips --gt " + ds(d) + " --renders " + renders(m, d) + " -o " + f);
      ASSERT_EQ(r.exit_code, 0) << r.output;
      files.push_back(f);
    }
  std::string all;
  for (const auto& f : files) all += " " + f;
  for (const char* fmt : {"md", "csv", "latex", "html"}) {
    const std::string out = dir / (std::string("board.") + fmt);
    auto r = run_command(kBin + " leaderboard" + all + " --format " + fmt + " -o " + out);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::string text = read_file(out);
    EXPECT_NE(text.find("yard"), std::string::npos) << fmt;
    EXPECT_NE(text.find("noise"), std::string::npos) << fmt;
  }
  // --note: under the title (md, html), a comment (latex); refused with csv before anything is written.
  const std::string note = "A smoke run at 1000 iterations, not converged";
  for (const char* fmt : {"md", "latex", "html"}) {
    const std::string out = dir / (std::string("noted.") + fmt);
    auto r = run_command(kBin + " leaderboard" + all + " --paper --format " + fmt + " --note '" + note + "' -o " + out);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(read_file(out).find(std::string(fmt) == "latex" ? "% " + note + "\n" : note), std::string::npos) << fmt;
  }
  auto noted_csv = run_command(kBin + " leaderboard" + all + " --format csv --note '" + note + "' -o " + (dir / "noted.csv"));
  EXPECT_EQ(noted_csv.exit_code, 2) << noted_csv.output;
  EXPECT_NE(noted_csv.output.find("--note"), std::string::npos) << noted_csv.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "noted.csv"));
  std::string md = read_file(dir / "board.md");
  EXPECT_NE(md.find("## Weather: Rain"), std::string::npos) << md;
  EXPECT_NE(md.find("## Weather: Snow"), std::string::npos) << md;
  EXPECT_NE(md.find("**"), std::string::npos) << md;

  // Check: results against themselves pass; a degraded copy fails with exit 1 and a readable report.
  const std::string base = files[0];
  auto same = run_command(kBin + " check --baseline " + base + " --results " + base);
  EXPECT_EQ(same.exit_code, 0) << same.output;
  EXPECT_NE(same.output.find("PASSED"), std::string::npos);
  Json j = read_json_file(base);
  j["metrics"]["psnr"] = j["metrics"]["psnr"].get<double>() - 0.5;
  write_file_atomic(dir / "worse.json", j.dump(2));
  auto worse = run_command(kBin + " check --baseline " + base + " --results " + (dir / "worse.json") + " --json " +
                           (dir / "report.json"));
  EXPECT_EQ(worse.exit_code, 1) << worse.output;
  EXPECT_NE(worse.output.find("FAIL"), std::string::npos) << worse.output;
  EXPECT_NE(worse.output.find("park_rain"), std::string::npos) << worse.output;
  EXPECT_EQ(read_json_file(dir / "report.json")["passed"], false);
  // A looser tolerance lets it pass.
  EXPECT_EQ(run_command(kBin + " check --baseline " + base + " --results " + (dir / "worse.json") + " --psnr-tol 1").exit_code, 0);
  // ... as does the baseline's own tolerances file; an explicit flag overrides it; unknown keys are errors.
  write_file_atomic(dir / "tol.json", R"({"psnr": 1.0, "basis": "test"})");
  const std::string with_file = kBin + " check --baseline " + base + " --results " + (dir / "worse.json") +
                                " --tolerances " + (dir / "tol.json");
  EXPECT_EQ(run_command(with_file).exit_code, 0);
  EXPECT_EQ(run_command(with_file + " --psnr-tol 0.1").exit_code, 1);
  write_file_atomic(dir / "tol2.json", R"({"psnr": 1.0, "psnr_tol": 2})");
  expect_bad_input(kBin + " check --baseline " + base + " --results " + base + " --tolerances " + (dir / "tol2.json"),
                   "'psnr_tol'", dir / "t.md");
  // Malformed and unknown-key results are bad input (exit 2), and no table is written.
  write_file_atomic(dir / "broken.json", "{");
  expect_bad_input(kBin + " leaderboard " + (dir / "broken.json") + " -o " + (dir / "t.md"), "broken.json", dir / "t.md");
  j = read_json_file(base);
  j["extra_key"] = 1;
  write_file_atomic(dir / "unknown.json", j.dump());
  expect_bad_input(kBin + " leaderboard " + (dir / "unknown.json") + " -o " + (dir / "t.md"), "'extra_key'", dir / "t.md");
  expect_bad_input(kBin + " check --baseline " + (dir / "unknown.json") + " --results " + base, "'extra_key'", dir / "t.md");
}

TEST_F(EvaluatorCli, ExportsNerfBaselinesLayoutMatchingItsReferenceHashes) {
  TempDir dir;
  const std::string res = dir / "r.json", out = dir / "nb";
  ASSERT_EQ(run_command(kBin + " --quiet evaluate --gt " + ds() + " --renders " + renders("box-blur") + " -o " + res)
                .exit_code, 0);
  const std::string cmd = kBin + " export-nerfbaselines --results " + res + " --data " + ds() + " --out " + out +
                          " --renders ";
  auto r = run_command(cmd + renders("box-blur"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"results.json", "predictions/info.json", "predictions/color/000.png",
                        "predictions/gt-color/008.png"})
    EXPECT_TRUE(fs::exists(fs::path(out) / f)) << f;
  // NerfBaselines' own hashing and encodings, re-implemented in Python from nerfbaselines/io.py.
  auto py = run_command("/usr/bin/python3 " + std::string(WEATHERGS_SOURCE_DIR) +
                        "/tests/evaluator/nerfbaselines_reference.py " + out + " " + res);
  EXPECT_EQ(py.exit_code, 0) << py.output;
  // An existing export is kept unless --force; renders that are not the scored ones are refused.
  expect_bad_input(cmd + renders("box-blur"), "--force", dir / "none");
  EXPECT_EQ(run_command(cmd + renders("box-blur") + " --force").exit_code, 0);
  const std::string other = copy_renders(renders("box-blur"), dir);
  fs::copy_file(other + "/008.png", other + "/000.png", fs::copy_options::overwrite_existing);
  expect_bad_input(kBin + " export-nerfbaselines --results " + res + " --data " + ds() + " --out " + (dir / "nb2") +
                       " --renders " + other,
                   "sha256.renders differs", dir / "nb2");
  // Masked metrics have no NerfBaselines equivalent.
  Json j = read_json_file(res);
  j["protocol"]["mask"] = "lens";
  write_file_atomic(dir / "masked.json", j.dump(2));
  expect_bad_input(kBin + " export-nerfbaselines --results " + (dir / "masked.json") + " --data " + ds() +
                       " --out " + (dir / "nb3") + " --renders " + renders("box-blur"),
                   "masked metrics", dir / "nb3");
}

// Flips the bits of one byte in the middle of a file.
void flip_byte(const std::string& path) {
  std::string bytes = read_file(path);
  bytes[bytes.size() / 2] = char(~bytes[bytes.size() / 2]);
  write_file_atomic(path, bytes);
}

// One byte of a weathered input changed (the ground truth untouched, so sha256.ground_truth cannot
// tell): evaluate refuses the dataset against its recorded identity; a regenerated copy (its record
// made anew) is scored, and then leaderboard and check refuse to put the two side by side.
TEST_F(EvaluatorCli, ADatasetWithOneByteChangedIsRefused) {
  TempDir dir;
  const std::string changed = dir / "park_rain";
  fs::copy(ds(), changed, fs::copy_options::recursive);
  const std::string a = dir / "a.json", b = dir / "b.json";
  const std::string eval = kBin + " --quiet evaluate --no-lpips --renders " + renders("noise") + " --gt ";
  ASSERT_EQ(run_command(eval + ds() + " -o " + a).exit_code, 0);
  const Json ja = read_json_file(a);
  const std::string id_a = ja.at("dataset_identity").at("sha256");
  EXPECT_EQ(ja.at("dataset_identity").at("scheme"), DatasetIdentity::kScheme);
  EXPECT_EQ(id_a, compute_dataset_identity(ds()).sha256);
  EXPECT_EQ(ja.at("dataset_identity").at("file_count"), 9 * 2 + 2) << "images/, clean/, cameras.json, splits";
  EXPECT_FALSE(ja.at("dataset_identity").contains("differs_from_recorded"));

  flip_byte(changed + "/images/008.png");
  expect_bad_input(eval + changed + " -o " + b, "images/008.png differs", b);
  auto refused = run_command(eval + changed + " -o " + b);
  EXPECT_NE(refused.output.find(changed), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("--allow-changed-dataset"), std::string::npos) << refused.output;
  // Scored anyway when asked, and the results say so.
  auto forced = run_command(eval + changed + " -o " + (dir / "forced.json") + " --allow-changed-dataset");
  ASSERT_EQ(forced.exit_code, 0) << forced.output;
  EXPECT_NE(forced.output.find("warning"), std::string::npos) << forced.output;
  const Json jf = read_json_file(dir / "forced.json");
  EXPECT_EQ(jf.at("dataset_identity").at("differs_from_recorded").at("first_difference"), "images/008.png differs");
  EXPECT_EQ(jf.at("dataset_identity").at("differs_from_recorded").at("sha256"), id_a);
  // Regenerated: the record made anew, then scored as any dataset.
  Json dj = read_json_file(changed + "/dataset.json");
  dj["identity"] = compute_dataset_identity(changed).to_json(true);
  write_file_atomic(changed + "/dataset.json", dj.dump(2));
  ASSERT_EQ(run_command(eval + changed + " -o " + b).exit_code, 0);
  const std::string id_b = read_json_file(b).at("dataset_identity").at("sha256");
  EXPECT_NE(id_b, id_a);
  EXPECT_EQ(read_json_file(b).at("sha256").at("ground_truth"), ja.at("sha256").at("ground_truth"));

  // leaderboard: one column, two datasets: refused naming both files and both hashes.
  const std::string board = dir / "board.md";
  auto lb = run_command(kBin + " leaderboard " + a + " " + b + " -o " + board);
  EXPECT_EQ(lb.exit_code, 2) << lb.output;
  for (const std::string& s : {a, b, id_a, id_b, std::string("--allow-mixed-data")})
    EXPECT_NE(lb.output.find(s), std::string::npos) << s << "\n" << lb.output;
  EXPECT_FALSE(fs::exists(board));
  EXPECT_EQ(run_command(kBin + " leaderboard --paper " + a + " " + b + " -o " + board).exit_code, 2);
  lb = run_command(kBin + " leaderboard --allow-mixed-data " + a + " " + b + " -o " + board);
  ASSERT_EQ(lb.exit_code, 0) << lb.output;
  const std::string md = read_file(board);
  EXPECT_NE(md.find("†"), std::string::npos) << md;
  EXPECT_NE(md.find(id_a.substr(0, 12)), std::string::npos) << md;
  EXPECT_NE(md.find(id_b.substr(0, 12)), std::string::npos) << md;
  // Results from before identities (none recorded) among them: not known to be on the same data.
  Json old = read_json_file(a);
  old.erase("dataset_identity");
  write_file_atomic(dir / "old.json", old.dump(2));
  EXPECT_EQ(run_command(kBin + " leaderboard " + a + " " + (dir / "old.json")).exit_code, 2);
  EXPECT_EQ(run_command(kBin + " leaderboard " + (dir / "old.json") + " " + (dir / "old.json")).exit_code, 0);

  // check: the baseline's data and the new data differ: refused, unless allowed, which it notes.
  auto chk = run_command(kBin + " check --baseline " + a + " --results " + b);
  EXPECT_EQ(chk.exit_code, 2) << chk.output;
  EXPECT_NE(chk.output.find(id_b), std::string::npos) << chk.output;
  EXPECT_NE(chk.output.find("--allow-other-data"), std::string::npos) << chk.output;
  chk = run_command(kBin + " check --allow-other-data --baseline " + a + " --results " + b);
  EXPECT_EQ(chk.exit_code, 0) << chk.output;
  EXPECT_NE(chk.output.find("other data than the baseline (allowed)"), std::string::npos) << chk.output;

  // A dataset that records no identity (made before identities, or by other tools) is scored with the computed one.
  dj = read_json_file(ds() + "/dataset.json");
  dj.erase("identity");
  fs::remove_all(changed);
  fs::copy(ds(), changed, fs::copy_options::recursive);
  write_file_atomic(changed + "/dataset.json", dj.dump(2));
  ASSERT_EQ(run_command(eval + changed + " -o " + (dir / "unrecorded.json")).exit_code, 0);
  EXPECT_EQ(read_json_file(dir / "unrecorded.json").at("dataset_identity").at("sha256"), id_a);
}

}  // namespace
}  // namespace weathergs
