#!/usr/bin/env bash
# Installs the dependencies, then checks formatting and the layer graph, builds the release
# configuration and runs every test in it: the newcomer's command, about 23 minutes on a fresh
# 2-core machine (docs/robustness.md, "Test stages and their cost").
#   bash scripts/test.sh --full   adds the same suite under AddressSanitizer + UBSan (minus the
#                                 slowest pure-physics tests, which the release stage runs), the
#                                 multi-threaded tests under ThreadSanitizer and a bounded
#                                 libFuzzer run of the scene loader and every mesh reader
#                                 (scripts/fuzz.sh, 15 s each). CI (.ci/run) runs --full.
# Each stage prints its wall time.
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in
  "" | --full) ;;
  *) echo "test.sh: unknown option '$1' (expected --full or nothing)" >&2; exit 2 ;;
esac
bash scripts/install-deps.sh --mpi

# ccache keys on paths relative to the checkout (the CMake launcher sets its base folder and
# leaves the working folder out of -g builds), so fresh clones reuse earlier builds.

# ctest runs two test programs at once on a 2-core machine: OpenMP threads that spin while
# waiting would steal the cores from each other's work (measured 13x slower), so they sleep.
export OMP_WAIT_POLICY=passive

# Warnings are errors in CI (CI=true), and only warnings elsewhere.
export GIPSI_WERROR=OFF
if [ "${CI:-}" = "true" ]; then export GIPSI_WERROR=ON; fi

echo "== clang-format"
mapfile -t sources < <(git ls-files '*.h' '*.cc' 2>/dev/null || find src apps tests plugins bench -name '*.h' -o -name '*.cc')
clang-format --dry-run --Werror "${sources[@]}"
echo "clang-format: ${#sources[@]} files formatted"

echo "== layers"
python3 scripts/check-layers.py

stage_start=$SECONDS
stage_done() { echo "== $1: $((SECONDS - stage_start)) s"; stage_start=$SECONDS; }

echo "== release"
cmake --preset release
cmake --build --preset release
ctest --preset release
stage_done release

# The installed package, used by an outside project (find_package(gipsi); docs/install.md).
echo "== package"
bash scripts/consumer-test.sh build/release
bash scripts/consumer-test.sh --deb build/release
# The core without Gmsh and OpenIGTLink (the same flags otherwise: ccache serves it).
bash scripts/minimal-test.sh
stage_done package

if [ "${1:-}" = "--full" ]; then
  # The slowest pure-physics tests (convergence studies on refined meshes and long
  # integrations, 3.5-12 s each in the release build; the resolved ventricle 70-225 s); the release stage runs them, and their
  # code paths are covered under the sanitizers by the smaller tests of the same solvers.
  asan_skip='^(FemSolid\.CantileverDeflectionConvergesToBeamTheory'
  asan_skip+='|Amg\.IterationsStayBoundedUnderRefinement|FemAmg\.CgIterationsStayBoundedUnderRefinement'
  asan_skip+='|MonodomainTest\.NagumoFrontSpeedConvergesAtSecondOrderInSpace'
  asan_skip+='|MonodomainTest\.AnisotropicIsochronesAreEllipsesThatRotateWithTheFibres'
  asan_skip+='|GridMonodomainTest\.AgreesWithTetsOnTheSlabAsBothAreRefined'
  asan_skip+='|GridMonodomainTest\.NagumoFrontSpeedConvergesAtSecondOrder'
  asan_skip+='|RuleBasedFibres\.TransmuralCoordinateConvergesToTheSphericalShell'
  asan_skip+='|MixedSolid\.LandBeamConvergesToTheBenchmarkWithoutLocking'
  asan_skip+='|MixedVentricle\.ContractionOnAResolvedWallKeepsItsVolumeAndIsMeshConverged'
  asan_skip+='|PhenomenologicalModels\.ProductionStepAgreesWithAHundredTimesFinerStep'
  asan_skip+='|TenTusscherPanfilov2006\.ProductionStepAgreesWithAHundredTimesFinerStep'
  # Whole-scene runs of 10-25 s in release (minutes under ASan); their code paths run under the
  # sanitizers in the smaller tests beside them (other Resume.* scenes, the haptic-path tests on
  # smaller blocks, GipsiValidate on bad inputs, the cavity-coupling tests).
  asan_skip+='|FemCondensation\.QuasiStaticIndentationThroughTheHapticPathMatchesTheFullModel'
  asan_skip+='|GipsiValidate\.AcceptsTheDemoScenes'
  asan_skip+='|FailurePolicy\.AFemSceneThatFailsAtItsStepSucceedsWithHalving'
  asan_skip+='|Resume\.FemIsBitwiseIdentical|Resume\.MonodomainIsBitwiseIdentical'
  asan_skip+='|Restep\.FemSolidQuasiStaticNewtonIsBitwise'
  # The heart's resume (three runs of the coupled heart, 10-30 s in release; minutes under ASan):
  # its kept-factorisation restore (numerics/newton_state.cc) is checked in the release stage.
  asan_skip+='|Resume\.HeartIsBitwiseIdentical'
  # Two beats of the 10.9k-tet heart and two coarser ones (about 25 s in release, past the
  # 300-s limit under ASan; clang 14 does not define __SANITIZE_ADDRESS__ for the test's own
  # skip). Its code paths are the default demo's, which runs under ASan.
  asan_skip+='|Heart\.FineMeshBeatsLikeTheDefaultDemoAndIsMeshConverged'
  # The viewer's window tests (gipsi view under Xvfb): Mesa's GL driver is unloaded before the
  # exit's leak check, so its one-time allocations show up from an "<unknown module>" that no
  # LeakSanitizer suppression can name (clang's ASan; gcc's did not report them). They run in
  # the release stage and under TSan; the viewer's simulation-side code (pull tool, display
  # managers, publishing) runs under ASan in the display and mouse-tool tests.
  asan_skip+='|Viewer\.(APullKeeps.*|AZeroLengthPull.*|Draws.*|TheMouse.*)'
  # A full disk simulated by the file-size limit: when its write fails, PLplot (5.15, Debian)
  # frees a pointer it never set (ASan's 0xbe fill pattern, SIGBUS in plend); the release stage
  # runs this test, where that pointer happens to be null. Not GiPSi's memory; to be worked
  # around by rendering plots into memory (noted for an issue).
  asan_skip+='|GipsiExitCodes\.AFullDiskExits4WithTheReasonAndLeavesNoPartialFile)$'
  # clang, whose ASan build compiles in about 60 % of gcc's time; the same tree builds the
  # libFuzzer targets that the fuzz stage runs, so the library is compiled once for both.
  echo "== asan (address + undefined behavior sanitizers, clang; with the libFuzzer targets)"
  cmake --preset asan
  cmake --build --preset asan
  ctest --preset asan -E "$asan_skip"
  stage_done asan

  # ThreadSanitizer (haptic loop, real-time probes in scenes, display publishing, viewer
  # simulation thread): 36 tests in 73 s on this machine (load average about 5); the build
  # mostly hits ccache after the first (cold: about 50 min of compilation under load,
  # docs/robustness.md).
  echo "== tsan (thread sanitizer: haptic loop, display publishing, viewer simulation thread)"
  cmake --preset tsan
  cmake --build --preset tsan
  ctest --preset tsan -E '^Viewer\.APullKeepsThe(HangingLiverRunning|HeartBeating|MassSpringHeartBeating)For10SimulatedSeconds$'
  stage_done tsan

  echo "== fuzz (libFuzzer, clang, ASan + UBSan; 15 s per target)"
  bash scripts/fuzz.sh 15
  stage_done fuzz
else
  echo "Release stage passed. 'bash scripts/test.sh --full' adds ASan + UBSan, TSan and fuzzing."
fi
