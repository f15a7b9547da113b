#!/usr/bin/env bash
# Several hosts (ctest label netns): the rig service in one network namespace, its controllers in
# another, joined only by a veth pair with test addresses (198.18.0.0/24, the benchmarking range)
# in namespaces the test creates and deletes; nothing touches the machine's own network. Two rigs
# under the same heave, `fixed` (choke held, open loop) and `controlled` (bhp_controller on the
# observer's estimate), lockstep clock: both controllers step their rig across the veth for 60 s of
# rig time, and the controlled rig's bottom-hole pressure swing must be at least 5x smaller, its
# mean within 0.05 bar (the same criteria as tests/clients/bhp_controller_test: measured 18.7x
# over loopback). Each controller ends with an error if it never reaches the service.
#
#   tests/deploy/netns_test.sh SOURCE_DIR BUILD_DIR MODE
# MODE:
#   unicast     deploy/cyclonedds-lab.xml as is: no multicast, the clients name the server as peer
#   multicast   Cyclone's multicast discovery on the veth, no peers at all (so discovery can only
#               have worked by multicast)
#   containers  as unicast, the service and the controllers in podman containers of the runtime
#               image, each container in its own namespace (podman --network ns:PATH)
# Exit 77 (skipped, with the reason) without root or network namespaces.
set -euo pipefail
src="$1" build="$2" mode="$3"
source "$src/tests/deploy/skip_unless_containers.sh"
need_root "network namespaces and veth pairs"
need_commands ip
[[ "$mode" == containers ]] && need_commands podman

ns_a="mpdrig-$$-a" ns_b="mpdrig-$$-b" veth_a="mpd$$a" veth_b="mpd$$b"
addr_a=198.18.0.1 addr_b=198.18.0.2
domain=12
work="$(mktemp -d /tmp/mpdrig-netns.XXXXXX)"
pids=()
containers=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  for c in "${containers[@]}"; do podman rm -f -t 1 "$c" >/dev/null 2>&1 || true; done
  ip netns del "$ns_a" 2>/dev/null || true  # deleting a namespace deletes its end of the veth
  ip netns del "$ns_b" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
ip netns add "$ns_a" 2>"$work/err" || skip "cannot create a network namespace: $(cat "$work/err")"
ip netns add "$ns_b"
ip link add "$veth_a" type veth peer name "$veth_b" 2>"$work/err" || skip "cannot create a veth pair: $(cat "$work/err")"
ip link set "$veth_a" netns "$ns_a"
ip link set "$veth_b" netns "$ns_b"
ip -n "$ns_a" addr add "$addr_a/24" dev "$veth_a"
ip -n "$ns_b" addr add "$addr_b/24" dev "$veth_b"
for ns in "$ns_a" "$ns_b"; do ip -n "$ns" link set lo up; done
ip -n "$ns_a" link set "$veth_a" up
ip -n "$ns_b" link set "$veth_b" up

lab_file="$src/deploy/cyclonedds-lab.xml"
case "$mode" in
  unicast|containers) config_a="file://$lab_file" config_b="file://$lab_file" ;;
  multicast)
    mc() { echo "<General><Interfaces><NetworkInterface address=\"$1\"/></Interfaces><AllowMulticast>true</AllowMulticast></General>"; }
    config_a="$(mc $addr_a)" config_b="$(mc $addr_b)" ;;
  *) echo "unknown mode $mode"; exit 2 ;;
esac

serve_args=(serve --clock lockstep --rate-hz 100 --heave-amp-m 0.1 --heave-hz 0.2 --pump-lpm 5
            --choke-deg 31 --sensor-noise none --rig fixed --rig controlled --domain "$domain")
control=(--lockstep --domain "$domain" --duration 60 --measure-last 20 --timeout 30)
start=$SECONDS
if [[ "$mode" != containers ]]; then
  ip netns exec "$ns_a" env MPDRIG_DDS_ADDRESS=$addr_a MPDRIG_RIG_HOST=$addr_a \
    "$build/tools/mpdrig" "${serve_args[@]}" --dds-config "$config_a" >"$work/serve.log" 2>&1 &
  pids+=($!)
  run_b() {
    ip netns exec "$ns_b" env MPDRIG_DDS_ADDRESS=$addr_b MPDRIG_RIG_HOST=$addr_a \
      "$build/clients/bhp_controller" "${control[@]}" --dds-config "$config_b" "$@"
  }
  run_b --rig fixed --open-loop >"$work/fixed.out" 2>"$work/fixed.err" &
  fixed_pid=$!
  run_b --rig controlled --use-estimate >"$work/controlled.out" 2>"$work/controlled.err" || true
  wait "$fixed_pid" || true
  cat "$work/fixed.out" "$work/controlled.out" >"$work/summary"
else
  source "$src/deploy/container/podman-env.sh"
  podman info >/dev/null 2>&1 || skip "podman cannot start: $(podman info 2>&1 | tail -1)"
  need_base_image_or_mirror
  BUILD_DIR="$build" "$src/deploy/container/build-images.sh"
  err="$(podman run --rm --network none "$MPDRIG_RUNTIME_IMAGE" true 2>&1)" ||
    skip "podman cannot run a container on this machine: $err"
  lab_in_image=file:///etc/mpdrig/cyclonedds-lab.xml
  containers+=("mpdrig-$$-rig")
  podman run -d --name "mpdrig-$$-rig" --network "ns:/run/netns/$ns_a" \
    -e MPDRIG_DDS_ADDRESS=$addr_a -e MPDRIG_RIG_HOST=$addr_a "$MPDRIG_RUNTIME_IMAGE" \
    mpdrig "${serve_args[@]}" --dds-config "$lab_in_image" >/dev/null
  containers+=("mpdrig-$$-ctl")
  podman run --name "mpdrig-$$-ctl" --network "ns:/run/netns/$ns_b" \
    -e MPDRIG_DDS_ADDRESS=$addr_b -e MPDRIG_RIG_HOST=$addr_a "$MPDRIG_RUNTIME_IMAGE" \
    bash -c "bhp_controller ${control[*]} --dds-config $lab_in_image --rig fixed --open-loop & f=\$!;
             bhp_controller ${control[*]} --dds-config $lab_in_image --rig controlled --use-estimate;
             wait \$f" >"$work/summary" 2>"$work/controllers.err" || true
  cat "$work/controllers.err" >"$work/controlled.err"
  podman logs "mpdrig-$$-rig" >"$work/serve.log" 2>&1 || true
fi
echo "mode $mode: ran in $((SECONDS - start)) s"
# (veth does not count multicast in its statistics; the multicast mode shows it by construction:
# no peers and loopback not selected leave multicast SPDP as the only way to discover.)
echo "received by the service's namespace over the veth: $(ip -n "$ns_a" -s link show "$veth_a" |
  awk '/RX:/ { getline; print $2 " packets" }')"

get() { sed -n "s/^rig=$1 .* $2=\([^ ]*\).*/\1/p" "$work/summary"; }
fixed_amp="$(get fixed PT1_amplitude_bar)" controlled_amp="$(get controlled PT1_amplitude_bar)"
if [[ -z "$fixed_amp" || -z "$controlled_amp" ]]; then
  echo "error: a controller did not finish its run across the veth"
  cat "$work/summary" "$work"/*.err "$work/serve.log" 2>/dev/null | tail -20
  exit 1
fi
cat "$work/summary"
awk -v f="$fixed_amp" -v c="$controlled_amp" -v fm="$(get fixed PT1_mean_barg)" \
    -v cm="$(get controlled PT1_mean_barg)" 'BEGIN {
  printf "PT1 swing: fixed %.4f bar, controlled %.4f bar, attenuated %.1fx; means %.4f / %.4f barg\n", f, c, f / c, fm, cm
  if (f <= 0.3) { print "error: the heave must move the BHP by tenths of a bar"; exit 1 }
  if (f / c < 5) { print "error: attenuated less than 5x"; exit 1 }
  d = cm - fm; if (d > 0.05 || -d > 0.05) { print "error: mean moved more than 0.05 bar"; exit 1 }
}'
