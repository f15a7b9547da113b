#!/bin/sh
# What the grader starts: the compiled controller on the grader's rig, in lockstep.
exec student-controller --lockstep --rig "$MPDRIG_RIG" --domain "$MPDRIG_DOMAIN" \
  --duration "$MPDRIG_DURATION_S" --timeout 30 --use-estimate
