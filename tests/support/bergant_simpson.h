// The Bergant & Simpson (1999) reservoir - pipe - valve rig as the repository's examples describe
// it (docs/examples/bergant-simpson-1999*.pbtxt, docs/bergant-simpson.md), for the tests that run
// it. Header-only; the including test target defines MPDRIG_SOURCE_DIR.
#pragma once

#include <string>

#include <gtest/gtest.h>

#include "model/config/rig_config.h"
#include "model/params/rig_params.h"

namespace mpdrig::testing {

// The severe case (1.4 m/s) and the moderate one (0.3 m/s).
inline const std::string kBergantSimpsonSevere =
    std::string(MPDRIG_SOURCE_DIR) + "/docs/examples/bergant-simpson-1999.pbtxt";
inline const std::string kBergantSimpsonModerate =
    std::string(MPDRIG_SOURCE_DIR) + "/docs/examples/bergant-simpson-1999-moderate.pbtxt";

// The rig of an example config (a failure is the test's, with the loader's message).
inline RigParams LoadExampleRig(const std::string& path) {
  auto params = LoadRigConfig(path);
  EXPECT_TRUE(params.ok()) << params.status().message();
  return params.ok() ? *params : RigParams();
}

}  // namespace mpdrig::testing
