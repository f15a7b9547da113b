#!/bin/sh
# Steps the rig but never moves the choke.
exec bhp_controller --lockstep --open-loop --rig "$MPDRIG_RIG" --domain "$MPDRIG_DOMAIN" \
  --duration "$MPDRIG_DURATION_S" --timeout 30
