#!/usr/bin/env bash
# Installs canalid's Debian package into a fresh Debian 12 root, as a user installs it, and checks
# what it installed. Builds the .deb with CPack from BINARY_DIR (that tree's build type: this tests
# the install rules and the package, not the Release build of scripts/package), makes the root with
# scripts/debian-root (mmdebstrap, systemd included), then inside it (chroot, /proc mounted in a
# private mount namespace that takes its mounts with it when it ends):
#   apt-get install ./canalid_<version>_amd64.deb, every program's --version, canalidd
#   --check-config on /etc/canalidd/canalidd.toml, canalsim --check-config on the installed canal
#   files, systemd-analyze verify of each installed unit (no output), the conffile in dpkg -s, and
#   no unit enabled. The package's contents and control members are checked on the host first.
# Needs root, mmdebstrap, dpkg-shlibdeps and the Debian mirror; fails saying which is missing.
# Usage: install_deb.sh SOURCE_DIR BINARY_DIR VERSION
set -euo pipefail
source_dir=$1
binary_dir=$2
version=$3

fail() {
  echo "FAIL $*"
  exit 1
}
[ "$(id -u)" -eq 0 ] || fail "needs root (mmdebstrap, chroot and mount)"
for tool in cpack mmdebstrap dpkg-shlibdeps unshare chroot; do
  command -v "$tool" >/dev/null 2>&1 || fail "$tool is missing (scripts/setup installs it)"
done

work=$(mktemp -d "${TMPDIR:-/tmp}/canalid-package-test.XXXXXX")
root=$work/root
cleanup() {
  # The mounts lived in the namespace of unshare, which has ended; never delete under a mount.
  if grep -q " $work/" /proc/self/mountinfo; then
    echo "FAIL something is still mounted under $work: left in place"
    exit 1
  fi
  rm -rf "$work"
}
trap cleanup EXIT

# 1. The package, and what is in it.
cpack --config "$binary_dir/CPackConfig.cmake" -G DEB -B "$work/out" >"$work/cpack.log" 2>&1 || {
  cat "$work/cpack.log"
  fail "cpack"
}
deb=$work/out/canalid_${version}_$(dpkg --print-architecture).deb
[ -f "$deb" ] || fail "cpack did not write $deb"
echo "ok   cpack $(basename "$deb") ($(stat -c %s "$deb") bytes)"

status=0
check() { # check DESCRIPTION COMMAND...: runs COMMAND, ok when it exits 0
  local what=$1
  shift
  if "$@"; then echo "ok   $what"; else
    echo "FAIL $what"
    status=1
  fi
}
mapfile -t files < <(dpkg-deb -c "$deb" | awk '$1 !~ /^d/ { print $6 }')
unexpected=$(printf '%s\n' "${files[@]}" | grep -Ev '^\./(usr/bin/(canalid|canalidd|canalid-command|canalsim)|usr/lib/systemd/system/[^/]+\.service|etc/canalidd/canalidd\.toml|usr/share/canalid/.+\.toml|usr/share/doc/canalid/.+)$' || true)
check "package holds only programs, units, configuration, examples and docs" test -z "$unexpected"
[ -z "$unexpected" ] || echo "$unexpected"
check "package holds the four programs" test "$(printf '%s\n' "${files[@]}" | grep -c '^\./usr/bin/')" -eq 4
dpkg-deb --ctrl-tarfile "$deb" | tar -t >"$work/control-members"
check "no maintainer scripts (nothing enabled or started)" \
  bash -c "! grep -Eq 'preinst|postinst|prerm|postrm|config$' '$work/control-members'"
depends=$(dpkg-deb -f "$deb" Depends)
check "Depends from dpkg-shlibdeps and procps: $depends" \
  bash -c "grep -q 'libmodbus5' <<<'$depends' && grep -q 'procps' <<<'$depends'"

# 2. A fresh Debian 12 root with systemd, and the package installed into it by apt.
"$source_dir/scripts/debian-root" "$root" systemd >"$work/debian-root.log" 2>&1 || {
  tail -20 "$work/debian-root.log"
  fail "scripts/debian-root (log above)"
}
echo "ok   fresh root $(du -sh "$root" | cut -f1)"
cp "$deb" "$root/tmp/"

# Everything inside the root runs in one chroot session; each check prints ok/FAIL itself.
cat >"$root/tmp/inside.sh" <<INSIDE
#!/bin/bash
set -u
export DEBIAN_FRONTEND=noninteractive LC_ALL=C.UTF-8
status=0
check() { local what=\$1; shift; if "\$@"; then echo "ok   \$what"; else echo "FAIL \$what"; status=1; fi; }
apt-get update -q >/tmp/apt.log 2>&1 && apt-get install -y -q /tmp/$(basename "$deb") >>/tmp/apt.log 2>&1 || {
  tail -30 /tmp/apt.log; echo "FAIL apt-get install of the package"; exit 1; }
echo "ok   apt-get install ./$(basename "$deb")"
for program in canalid canalidd canalid-command canalsim; do
  check "\$program --version = \$program $version" test "\$(\$program --version 2>&1)" = "\$program $version"
done
check "canalidd --check-config /etc/canalidd/canalidd.toml" \
  canalidd --config /etc/canalidd/canalidd.toml --check-config
check "canalsim run --check-config on /usr/share/canalid/sim" canalsim run --check-config \
  --canal /usr/share/canalid/sim/asce-canal2.toml \
  --scenario /usr/share/canalid/sim/scenarios/asce2-pool2-prbs.toml
for unit in canalidd.service canalsim.service canalid-logger@site1.service; do
  out=\$(cd /lib/systemd/system && systemd-analyze verify --man=no "\$unit" 2>&1)
  rc=\$?
  check "systemd-analyze verify /lib/systemd/system/\$unit: exit 0 (\$rc) and no output" \
    test "\$rc" -eq 0 -a -z "\$out"
  [ -z "\$out" ] || echo "\$out"
done
check "conffile /etc/canalidd/canalidd.toml in dpkg -s canalid" \
  bash -c "dpkg -s canalid | sed -n '/^Conffiles:/,/^[^ ]/p' | grep -q '^ /etc/canalidd/canalidd.toml '"
for unit in canalidd canalsim canalid-logger@site1; do
  state=\$(systemctl is-enabled "\$unit" 2>&1)
  check "\$unit not enabled (systemctl is-enabled: \$state)" test "\$state" = disabled
done
check "no canalid unit linked in /etc/systemd/system" \
  test -z "\$(find /etc/systemd/system -name 'canali*' 2>/dev/null)"
exit \$status
INSIDE
chmod 755 "$root/tmp/inside.sh"
unshare --mount --propagation private -- \
  bash -c 'mount -t proc proc "$1/proc" && exec chroot "$1" /tmp/inside.sh' _ "$root" || status=1
exit $status
