// Seeded mutation fuzzing of the config parser (tests/support/mutator.h): thousands of mutated
// Protobuf text configs. What must hold for every input: no crash (and no sanitizer report in the
// ASan/UBSan build), an error names the source, and a config that is accepted is a valid one
// (RigParams::Validate and the effect registry agree). A failure prints the seed and the
// iteration; MPDRIG_FUZZ_SEED and MPDRIG_FUZZ_ITERATIONS rerun or extend it.
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/config/rig_config.h"
#include "model/effects/effect.h"
#include "model/params/rig_params.h"
#include "tests/support/mutator.h"

namespace mpdrig {
namespace {

std::vector<std::string> SeedConfigs() {
  RigParams params;
  EXPECT_TRUE(ApplyEffectSpec(&params, "sensor_lag:time_constant_s=0.2").ok());
  return {FormatRigConfig(RigParams()), FormatRigConfig(params),
          "wave_speed_mps: 1000\npipe_length_m: 900\n",
          "choke_point { opening_deg: 0 g_m2: 0 }\nchoke_point { opening_deg: 45 g_m2: 5e-5 }\n"
          "choke_point { opening_deg: 90 g_m2: 1.03e-4 }\n",
          "effect {\n  name: \"unsteady_friction\"\n  param { key: \"k\" value: 0.03 }\n}\n"
          "upper_rod_diameter_m: 0.04\nlower_rod_diameter_m: 0.02\n"};
}

TEST(RigConfigFuzz, MutatedConfigsParseToValidParamsOrFailNamingTheSource) {
  const std::uint64_t seed = testing::FuzzSeed(20261125);
  const long iterations = testing::FuzzIterations(50000);
  testing::Mutator mutator(SeedConfigs(), seed);
  long accepted = 0;
  for (long i = 0; i < iterations; ++i) {
    const std::string text = mutator.Next();
    auto parsed = ParseRigConfig(text, "fuzz.pbtxt");
    if (!parsed.ok()) {
      ASSERT_EQ(parsed.status().message().rfind("fuzz.pbtxt:", 0), 0u)
          << "seed " << seed << ", iteration " << i << ": " << parsed.status().message()
          << "\ninput:\n"
          << text;
      continue;
    }
    ++accepted;
    const Status valid = parsed->Validate();
    ASSERT_TRUE(valid.ok()) << "seed " << seed << ", iteration " << i
                            << ": accepted an invalid config: " << valid.message() << "\ninput:\n"
                            << text;
    const Status effects = ValidateEffects(*parsed);
    ASSERT_TRUE(effects.ok()) << "seed " << seed << ", iteration " << i
                              << ": accepted bad effects: " << effects.message() << "\ninput:\n"
                              << text;
  }
  std::printf("%ld mutated configs (seed %llu): %ld accepted\n", iterations,
              static_cast<unsigned long long>(seed), accepted);
  // Both outcomes must occur, or the mutations are too mild or too wild to test much.
  EXPECT_GT(accepted, iterations / 50);
  EXPECT_LT(accepted, iterations - iterations / 50);
}

}  // namespace
}  // namespace mpdrig
