# Sourced by the scripts that run furutad --sim over UDP multicast in a namespace of their own (the
# UDP test, the e-stop flood benchmark). Needs a fail function.
#
# udp_rig_config SOURCE_TOML CONFIG URL LOGS DIR: writes CONFIG from SOURCE_TOML with the run's LCM
# URL and logs directory, every key and the replay state file in DIR, no wait for the pendulum to
# hang still between sessions (a session a safety rule ended leaves it swinging for minutes), and a
# bang-bang that flips at 20 deg: at duty 0.15, room for loop stalls of about half a second before
# the arm reaches its 150 deg limit (as the crash trials). Fails naming any key it could not set.
udp_rig_config() {
  local source=$1 config=$2 url=$3 logs=$4 dir=$5 key
  sed -e "s|^lcm_url = .*|lcm_url = \"$url\"|" \
      -e "s|^logs_dir = .*|logs_dir = \"$logs\"|" \
      -e "s|^rest_check_s = .*|rest_check_s = 0.0|" \
      -e "s|^command_key_file = .*|command_key_file = \"$dir/command.key\"|" \
      -e "s|^command_state_file = .*|command_state_file = \"$dir/command-replay.state\"|" \
      -e "s|^daemon_key_file = .*|daemon_key_file = \"$dir/daemon.key\"|" \
      -e "s|^daemon_public_key_file = .*|daemon_public_key_file = \"$dir/daemon.pub\"|" \
      -e "s|^arm_switch_deg = [0-9.]*|arm_switch_deg = 20|" "$source" > "$config"
  grep -q "^lcm_url = \"$url\"" "$config" || fail "could not set lcm_url in the [daemon] table"
  grep -q "^logs_dir = \"$logs\"" "$config" || fail "could not set logs_dir in the [daemon] table"
  grep -q "^rest_check_s = 0.0$" "$config" || fail "could not set rest_check_s in the [daemon] table"
  for key in command_key_file command_state_file daemon_key_file daemon_public_key_file; do
    grep -q "^$key = \"$dir/" "$config" || fail "could not set $key in the [daemon] table"
  done
  grep -q "^arm_switch_deg = 20 " "$config" || fail "could not set arm_switch_deg in [excitation]"
}
