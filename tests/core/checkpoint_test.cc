// Checkpoints: the typed state format, checkpoint files, bitwise-identical continuation of real
// scenes through `gipsi run --resume`, and the roll-back failure policy.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "apps/cli_test_util.h"
#include "gipsi/base/error.h"
#include "gipsi/base/state.h"
#include "gipsi/core/kernel.h"
#include "test_paths.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

std::string ReadAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Every file under `dir` (relative path → bytes), checkpoints excluded.
std::map<std::string, std::string> Tree(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    const std::string ext = entry.path().extension().string();
    if (ext == ".gck" || ext == ".tmp") continue;
    files[fs::relative(entry.path(), dir).string()] = ReadAll(entry.path());
  }
  return files;
}

// --- The state format ---

TEST(State, RoundTripsEveryTypeBitForBit) {
  StateWriter out;
  out.BeginSection("Thing", 3);
  out.WriteDouble(0.1 + 0.2);
  out.WriteInt(-42);
  out.WriteBool(true);
  out.WriteString("valve 'aortic'");
  out.WriteArray(std::vector<int>{1, -2, 3});
  Eigen::MatrixXd m(2, 3);
  m << 1, 2, 3, 4, 5, std::nextafter(6.0, 7.0);
  out.WriteMatrix(m);
  out.EndSection();

  StateReader in(out.bytes(), "test");
  in.BeginSection("Thing", 3);
  EXPECT_EQ(in.ReadDouble(), 0.1 + 0.2);  // exact: stored bit for bit
  EXPECT_EQ(in.ReadInt(), -42);
  EXPECT_TRUE(in.ReadBool());
  EXPECT_EQ(in.ReadString(), "valve 'aortic'");
  std::vector<int> ints;
  in.ReadArray(ints);
  EXPECT_EQ(ints, (std::vector<int>{1, -2, 3}));
  Eigen::MatrixXd back(2, 3);
  in.ReadMatrixExact(back, "m");
  EXPECT_EQ(back, m);
  in.EndSection();
  EXPECT_TRUE(in.at_end());
}

TEST(State, MismatchesAreClearErrors) {
  StateWriter out;
  out.BeginSection("MassSpring", 1);
  out.WriteMatrix(Eigen::VectorXd::Zero(6));
  out.EndSection();
  {
    StateReader in(out.bytes(), "ck.gck");
    try {
      in.BeginSection("FemSolid", 1);
      FAIL() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("ck.gck"));
      EXPECT_THAT(e.what(), HasSubstr("expected state of 'FemSolid'"));
      EXPECT_THAT(e.what(), HasSubstr("'MassSpring'"));
    }
  }
  {
    StateReader in(out.bytes(), "ck.gck");
    EXPECT_THROW(in.BeginSection("MassSpring", 2), InputError);  // another format version
  }
  {
    StateReader in(out.bytes(), "ck.gck");
    in.BeginSection("MassSpring", 1);
    Eigen::VectorXd x(9);
    try {
      in.ReadMatrixExact(x, "the state");
      FAIL() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("MassSpring: the state is 6 by 1 in the checkpoint but 9 "
                                      "by 1 in this scene"));
    }
  }
  {
    StateReader in(out.bytes(), "ck.gck");
    in.BeginSection("MassSpring", 1);
    EXPECT_THROW((void)in.ReadDouble(), InputError);  // a matrix is stored here
  }
  {
    StateReader in(out.bytes().substr(0, out.bytes().size() - 5), "ck.gck");
    EXPECT_THROW(in.BeginSection("MassSpring", 1), InputError);  // truncated section
  }
}

TEST(CheckpointFile, TruncatedOrCorruptedFilesAreRefused) {
  const fs::path dir = testing::TempDir("gipsi_ckpt_", "file");
  const fs::path file = dir / "a.gck";
  const std::string payload(1000, 'x');
  WriteCheckpointFile(file, payload);
  EXPECT_EQ(ReadCheckpointFile(file), payload);
  EXPECT_FALSE(fs::exists(dir / "a.gck.tmp"));

  const std::string good = ReadAll(file);
  auto expect_error = [&](const std::string& bytes, const std::string& what) {
    std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
    try {
      (void)ReadCheckpointFile(file);
      ADD_FAILURE() << "expected InputError for " << what;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(file.string()));
      EXPECT_THAT(e.what(), HasSubstr(what));
    }
  };
  expect_error(good.substr(0, good.size() - 1), "truncated");
  expect_error(good.substr(0, 10), "bad magic");
  std::string flipped = good;
  flipped[flipped.size() - 3] ^= 1;
  expect_error(flipped, "corrupted");
  expect_error("{\"gipsi\": 1}", "not a GiPSi checkpoint");
}

TEST(CheckpointFile, AnInterruptedWriteLeavesThePreviousCheckpoint) {
  // A process killed while writing leaves a partial temporary file; the checkpoint itself is
  // only ever replaced by rename, so it is still the previous complete one.
  const fs::path dir = testing::TempDir("gipsi_ckpt_", "killed");
  const fs::path file = dir / "run.gck";
  WriteCheckpointFile(file, "state at t = 1");
  std::ofstream(dir / "run.gck.tmp", std::ios::binary) << "GIPSI-CHECKPOINT-1\npartial";
  EXPECT_EQ(ReadCheckpointFile(file), "state at t = 1");
  // The next checkpoint replaces the stale temporary file.
  WriteCheckpointFile(file, "state at t = 2");
  EXPECT_EQ(ReadCheckpointFile(file), "state at t = 2");
  EXPECT_FALSE(fs::exists(dir / "run.gck.tmp"));
}

// --- Bitwise-identical continuation through the command line ---

/// Runs `scene` to `end` in one go, and again interrupted: a first run to `stop` (past the last
/// checkpoint, so it also wrote outputs the resumed run must discard) writing checkpoints every
/// `every`, then `--resume` from the last checkpoint to `end`. Every output file must be
/// bitwise identical.
void ExpectBitwiseResume(const std::string& scene, const std::string& name, double every,
                         double stop, double end, const std::string& extra = "") {
  const std::string path = std::string(GIPSI_SOURCE_DIR) + "/scenes/" + scene;
  const fs::path once = testing::TempDir("gipsi_resume_", name + "_once");
  const fs::path split = testing::TempDir("gipsi_resume_", name + "_split");
  auto r =
      testing::Gipsi(fmt::format("run {} -q --until {} -o {} {}", path, end, once.string(), extra));
  ASSERT_EQ(r.code, 0) << r.output;
  r = testing::Gipsi(fmt::format("run {} -q --until {} --checkpoint-every {} -o {} {}", path, stop,
                                 every, split.string(), extra));
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_TRUE(fs::exists(split / "checkpoint.gck"));
  r = testing::Gipsi(fmt::format("run {} -q --until {} --resume {} -o {} {}", path, end,
                                 (split / "checkpoint.gck").string(), split.string(), extra));
  ASSERT_EQ(r.code, 0) << r.output;
  const auto a = Tree(once), b = Tree(split);
  ASSERT_FALSE(a.empty());
  for (const auto& [file, bytes] : a) {
    auto it = b.find(file);
    ASSERT_NE(it, b.end()) << file << " is missing after the resumed run";
    EXPECT_TRUE(it->second == bytes) << file << " differs after the resumed run";
  }
  EXPECT_EQ(a.size(), b.size());
}

TEST(Resume, MassSpringAcrossAnEventIsBitwiseIdentical) {
  // Checkpoint at 1.0 s, the first run goes on to 1.2 s, the corner is released at 1.5 s.
  ExpectBitwiseResume("hanging_sheet.json", "sheet", 0.5, 1.2, 2.0);
}

TEST(Resume, AggregateWithBoundaryCouplingIsBitwiseIdentical) {
  ExpectBitwiseResume("coupled_blocks.json", "blocks", 0.01, 0.025, 0.04, "--no-vtu");
}

TEST(Resume, FemIsBitwiseIdentical) {
  ExpectBitwiseResume("cantilever.json", "fem", 0.05, 0.07, 0.12);
}

TEST(Resume, DynamicMixedSolidIsBitwiseIdentical) {
  // BDF2's history, the incompressible pressure and Newton's kept factorisation all resume.
  ExpectBitwiseResume("cantilever_p2.json", "mixed", 0.05, 0.07, 0.12);
}

TEST(Resume, FemThroughTheOdeContractIsBitwiseIdentical) {
  ExpectBitwiseResume("cantilever_explicit.json", "fem_ode", 0.05, 0.07, 0.12);
}

TEST(Resume, MonodomainIsBitwiseIdentical) {
  ExpectBitwiseResume("slab_ep_grid_0.5mm.json", "ep", 0.001, 0.0015, 0.003);
}

TEST(Resume, CirculationIsBitwiseIdentical) {
  ExpectBitwiseResume("circulation_closed_loop.json", "blood", 0.4, 0.5, 1.0);
}

TEST(Resume, HeartIsBitwiseIdentical) {
  // The coupled heart (monodomain, FEM wall whose Newton solver keeps its factorisation from
  // step to step, cavity pressure solved with the wall, closed-loop blood, beat monitor):
  // checkpoint at 0.1 s, in the first beat's contraction (stimulus at t = 0), resumed to 0.25 s.
  ExpectBitwiseResume("heart.json", "heart", 0.1, 0.12, 0.25);
}

TEST(Resume, MassSpringHeartIsBitwiseIdentical) {
  // The mass-spring heart: the explicit wall's state, active tension, fibres and the cavity's
  // pressure and blood-compliance estimate (the pressure solve's starting point) are saved, so
  // the continuation is bitwise identical; checkpoint at 0.1 s, in the first contraction.
  ExpectBitwiseResume("heart_mass_spring.json", "heart_ms", 0.1, 0.12, 0.25);
}

TEST(Resume, MixedHeartIsBitwiseIdentical) {
  // The heart with its incompressible P2-P1 muscle: the cavity pressure solved with the wall (a
  // bordered unknown of Newton), the kept UMFPACK factorisation and the predictor's history;
  // checkpoint at 20 ms, resumed to 50 ms.
  ExpectBitwiseResume("heart_mixed.json", "heart_mixed", 0.02, 0.03, 0.05);
}

TEST(Resume, HapticPalpationIsBitwiseIdentical) {
  // The multi-rate haptic demo: an FEM liver, a synchronous probe on a scripted path ticking at
  // 1 kHz and the coupling that publishes local models. The contact starts at about 1.18 s;
  // checkpoint at 1.3 s, pressing, with the tick's local state, hand-over blend and safety
  // stage, the bridge's kept contact and both buffers (with an unfetched model) to restore.
  ExpectBitwiseResume("liver_palpation.json", "palpation", 0.65, 1.35, 1.5);
}

TEST(Resume, ACheckpointOfAnotherSceneIsRefused) {
  const fs::path dir = testing::TempDir("gipsi_resume_", "other");
  const std::string scenes = std::string(GIPSI_SOURCE_DIR) + "/scenes/";
  auto r =
      testing::Gipsi(fmt::format("run {}hanging_sheet.json -q --until 0.01 "
                                 "--checkpoint-every 0.01 --no-vtu -o {}",
                                 scenes, dir.string()));
  ASSERT_EQ(r.code, 0) << r.output;
  r =
      testing::Gipsi(fmt::format("run {}circulation_windkessel.json -q --until 0.02 --resume {} "
                                 "-o {}",
                                 scenes, (dir / "checkpoint.gck").string(), dir.string()));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_THAT(r.output, HasSubstr("checkpoint.gck"));
  EXPECT_THAT(r.output, HasSubstr("another scene"));
}

TEST(Resume, ARefusedResumeLeavesEveryOutputFileUntouched) {
  // A first run writes VTU series, probe CSVs and a checkpoint at 0.1 s, and goes on to 0.15 s.
  const std::string scene = std::string(GIPSI_SOURCE_DIR) + "/scenes/hanging_sheet.json";
  const fs::path dir = testing::TempDir("gipsi_resume_", "refused");
  auto r = testing::Gipsi(
      fmt::format("run {} -q --until 0.15 --checkpoint-every 0.1 -o {}", scene, dir.string()));
  ASSERT_EQ(r.code, 0) << r.output;
  const auto before = Tree(dir);
  ASSERT_EQ(before.count("sheet.pvd"), 1u);
  ASSERT_EQ(before.count("probes/centre.csv"), 1u);

  // A corrupted checkpoint is refused before anything is restored.
  std::string bytes = ReadAll(dir / "checkpoint.gck");
  bytes[bytes.size() / 2] ^= 1;
  std::ofstream(dir / "corrupt.gck", std::ios::binary) << bytes;
  r = testing::Gipsi(fmt::format("run {} -q --until 0.2 --resume {} -o {}", scene,
                                 (dir / "corrupt.gck").string(), dir.string()));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_THAT(r.output, HasSubstr("corrupted"));
  EXPECT_TRUE(Tree(dir) == before) << "a refused resume changed the outputs";

  // A scene whose probes differ is refused by the probe recorder, after the objects and the VTU
  // series (restored first) have read their state: the series' collections are left alone too.
  std::ifstream in(scene);
  nlohmann::json json = nlohmann::json::parse(in);
  json["probes"]["middle"] = json["probes"]["centre"];
  json["probes"].erase("centre");
  const fs::path other = testing::TempDir("gipsi_resume_", "refused_scene");
  std::ofstream(other / "scene.json") << json.dump();
  r = testing::Gipsi(fmt::format("run {} -q --until 0.2 --resume {} -o {}",
                                 (other / "scene.json").string(), (dir / "checkpoint.gck").string(),
                                 dir.string()));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_THAT(r.output, HasSubstr("other probes"));
  EXPECT_TRUE(Tree(dir) == before) << "a refused resume changed the outputs";
  EXPECT_FALSE(fs::exists(dir / "probes" / "middle.csv"));

  // The good checkpoint still resumes (and cuts the files back to 0.1 s before going on).
  r = testing::Gipsi(fmt::format("run {} -q --until 0.2 --resume {} -o {}", scene,
                                 (dir / "checkpoint.gck").string(), dir.string()));
  EXPECT_EQ(r.code, 0) << r.output;
}

// --- Roll-back and retry ---

/// dx/dt = −k x by forward Euler, which reports divergence when the step is unstable
/// (k dt > 1: the amplification factor 1 − k dt would be negative).
class DecayObject final : public SimObject {
 public:
  explicit DecayObject(double k) : SimObject("decay"), k_(k) {
    DeclareField({"x", FieldLocation::kGlobal, 1, "1", FieldAccess::kRead, "state"});
  }
  std::string_view type_name() const override { return "Decay"; }
  const Points& domain_positions() const override { return none_; }
  void SaveObjectState(StateWriter& out) const override { out.WriteDouble(x_); }
  void RestoreObjectState(StateReader& in) override { x_ = in.ReadDouble(); }
  [[nodiscard]] double x() const { return x_; }

 protected:
  StepStatus DoStep(double, double dt) override {
    x_ *= 1 - k_ * dt;
    if (k_ * dt > 1) {
      x_ = std::numeric_limits<double>::quiet_NaN();  // what a blown-up solver leaves
      return StepStatus::Diverged("unstable step", -1, k_ * dt);
    }
    return StepStatus::Ok();
  }
  void DoReadField(FieldId, Eigen::Ref<Eigen::MatrixXd> out) const override { out(0, 0) = x_; }
  void DoWriteField(FieldId, const Eigen::Ref<const Eigen::MatrixXd>&) override {}

 private:
  double k_;
  double x_ = 1;
  Points none_ = Points(3, 0);
};

/// Records x after every macro step.
class XRecorder final : public Observer {
 public:
  explicit XRecorder(std::vector<double>& xs) : xs_(xs) {}
  void Observe(const Kernel& kernel, double) override {
    xs_.push_back(static_cast<const DecayObject&>(kernel.coordinator().object(0)).x());
  }

 private:
  std::vector<double>& xs_;
};

TEST(FailurePolicy, RetriesWithHalvedStepsAndNeverOutputsNaN) {
  // k = 12 /s, macro step 0.125 s: k dt = 1.5 diverges; halved, k dt = 0.75 is stable, so each
  // macro step becomes two Euler steps and x_n = (1 − 0.75)^(2n) = 0.25^(2n): every number
  // here is a power of two or a short binary fraction, so the comparison is exact.
  Kernel kernel;
  kernel.coordinator().AddObject(std::make_unique<DecayObject>(12.0), 0.125);
  std::vector<double> xs;
  kernel.AddObserver(std::make_unique<XRecorder>(xs));
  kernel.Initialize();
  kernel.SetFailurePolicy({.max_halvings = 3});
  const RunResult result = kernel.Run(0.625);
  ASSERT_TRUE(result.ok()) << result.diagnostic;
  EXPECT_EQ(kernel.retried_steps(), 5);
  ASSERT_EQ(xs.size(), 6u);  // the start and 5 macro steps
  for (std::size_t n = 0; n < xs.size(); ++n)
    EXPECT_EQ(xs[n], std::pow(0.25, 2.0 * static_cast<double>(n))) << n;
  EXPECT_EQ(kernel.time(), 0.625);
  EXPECT_EQ(kernel.coordinator().object(0).time(), 0.625);
}

TEST(FailurePolicy, StopsAfterTheLastHalvingAndKeepsTheLastGoodState) {
  // k = 100 /s, macro step 0.125 s: even a quarter step (k dt = 3.125) diverges.
  Kernel kernel;
  kernel.coordinator().AddObject(std::make_unique<DecayObject>(100.0), 0.125);
  std::vector<double> xs;
  kernel.AddObserver(std::make_unique<XRecorder>(xs));
  kernel.Initialize();
  kernel.SetFailurePolicy({.max_halvings = 2});
  const RunResult result = kernel.Run(0.5);
  EXPECT_EQ(result.outcome, RunResult::Outcome::kDiverged);
  EXPECT_THAT(result.diagnostic, HasSubstr("object 'decay' diverged"));
  EXPECT_THAT(result.diagnostic, HasSubstr("halved 2 times"));
  ASSERT_EQ(xs.size(), 1u);  // only the initial state was output
  EXPECT_EQ(xs[0], 1.0);
  const auto& decay = static_cast<const DecayObject&>(kernel.coordinator().object(0));
  EXPECT_EQ(decay.x(), 1.0);  // rolled back, not NaN
}

TEST(FailurePolicy, TheDefaultStopsAtTheFirstFailure) {
  Kernel kernel;
  kernel.coordinator().AddObject(std::make_unique<DecayObject>(12.0), 0.125);
  kernel.Initialize();
  const RunResult result = kernel.Run(0.625);
  EXPECT_EQ(result.outcome, RunResult::Outcome::kDiverged);
  EXPECT_EQ(kernel.retried_steps(), 0);
}

/// The cantilever scene with object step `dt`, no internal bisection of failed Newton solves and
/// a residual-only Newton line search, ending at 0.1 s, with `on_failure` if not null; returns
/// its final mean tip z-displacement (NaN if the run failed) and the run's output.
std::pair<double, testing::Result> RunCantilever(const std::string& name, double dt,
                                                 const nlohmann::json& on_failure) {
  std::ifstream in(std::string(GIPSI_SOURCE_DIR) + "/scenes/cantilever.json");
  nlohmann::json scene = nlohmann::json::parse(in);
  scene["objects"]["beam"]["dt"] = dt;
  scene["objects"]["beam"]["max_bisections"] = 0;
  // Newton's residual-only line search, which fails the 0.02 s steps of this scene (the default
  // natural monotonicity test converges even 0.1 s steps: a failure is needed here).
  scene["objects"]["beam"]["newton"] = {{"monotonicity_test", false}};
  scene["schedule"]["end"] = 0.1;
  if (!on_failure.is_null()) scene["schedule"]["on_failure"] = on_failure;
  scene["outputs"] = {{"vtu", false}};
  const fs::path dir = testing::TempDir("gipsi_retry_", name);
  std::ofstream(dir / "scene.json") << scene.dump();
  testing::Result r = testing::Gipsi(
      fmt::format("run {} -o {}", (dir / "scene.json").string(), (dir / "out").string()));
  double z = std::numeric_limits<double>::quiet_NaN();
  std::ifstream csv(dir / "out" / "probes" / "tip.csv");
  std::string line, last;
  std::getline(csv, line);  // header
  while (std::getline(csv, line)) {
    EXPECT_EQ(line.find("nan"), std::string::npos) << name << ": " << line;
    EXPECT_EQ(line.find("inf"), std::string::npos) << name << ": " << line;
    last = line;
  }
  if (r.code == 0) z = std::stod(last.substr(last.rfind(',') + 1));
  return {z, r};
}

TEST(FailurePolicy, AFemSceneThatFailsAtItsStepSucceedsWithHalving) {
  // 0.02 s steps are too large for Newton on the falling cantilever (no internal bisection).
  const auto [z_stop, stop] = RunCantilever("stop", 0.02, nullptr);
  EXPECT_EQ(stop.code, 3) << stop.output;
  EXPECT_THAT(stop.output, HasSubstr("Newton did not converge"));
  const nlohmann::json retry = {{"retry", {{"max_halvings", 2}}}};
  const auto [z_retry, retried] = RunCantilever("retry", 0.02, retry);
  ASSERT_EQ(retried.code, 0) << retried.output;
  EXPECT_THAT(retried.output, HasSubstr("retried steps:"));
  // The retried run takes (mostly) 0.01 s backward-Euler steps. It must agree with a run of
  // 0.01 s steps to within that run's own first-order time error, estimated (Richardson) by
  // its difference from a run of 0.005 s steps.
  const auto [z_01, r_01] = RunCantilever("ref01", 0.01, nullptr);
  const auto [z_005, r_005] = RunCantilever("ref005", 0.005, nullptr);
  ASSERT_EQ(r_01.code, 0) << r_01.output;
  ASSERT_EQ(r_005.code, 0) << r_005.output;
  EXPECT_LT(std::abs(z_retry - z_01), std::abs(z_01 - z_005));
  EXPECT_LT(z_retry, -0.05);  // the beam has sagged by several centimetres
}

TEST(FailurePolicy, SceneKeyIsCheckedWithItsPath) {
  const auto [z, r] = RunCantilever("bad", 0.01, {{"retry", {{"max_halvings", 0}}}});
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_THAT(r.output, HasSubstr("schedule.on_failure.retry.max_halvings"));
  EXPECT_THAT(r.output, HasSubstr("an integer from 1 to 20"));
  const auto [z2, r2] = RunCantilever("bad2", 0.01, "retry");
  EXPECT_EQ(r2.code, 1) << r2.output;
  EXPECT_THAT(r2.output, HasSubstr("schedule.on_failure"));
}

}  // namespace
}  // namespace gipsi
