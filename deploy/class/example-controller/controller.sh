#!/bin/sh
# The example "student": the project's bhp_controller on the observer's estimate, with gains of
# its own choosing. The grader passes the rig, domain and run length in the environment; the rig
# runs in lockstep, so the controller steps it.
exec bhp_controller --lockstep --rig "$MPDRIG_RIG" --domain "$MPDRIG_DOMAIN" \
  --duration "$MPDRIG_DURATION_S" --timeout 30 --use-estimate
