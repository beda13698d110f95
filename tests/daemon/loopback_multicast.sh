# Sourced by the tests that run furutad over UDP multicast inside their own network namespace
# (unshare -rn): loopback up, multicast routed to it, and a group and port of this run's own in
# GROUP, PORT and URL (the namespace isolates the run already; this keeps its traffic apart from
# anything else listening on the default). Needs a fail function.
ip link set lo up || fail "cannot bring lo up in the namespace"
ip route add 224.0.0.0/4 dev lo || fail "cannot route multicast to lo"
GROUP="239.255.$((RANDOM % 250 + 1)).$((RANDOM % 250 + 1))"
PORT=$((20000 + RANDOM % 20000))
URL="udpm://$GROUP:$PORT?ttl=0"
