#!/usr/bin/env bash
# What `./dev test` does on a fresh Debian whose python3 lacks python3-venv (issue 16, class 11).
#
# Simulation (no container available): a private mount namespace (`unshare -m`, needs root) in
# which an empty tmpfs hides /usr/lib/python3.X/ensurepip, the files python3.X-venv installs, so
# Debian's own /usr/bin/python3 behaves exactly as without python3-venv; PATH starts with a fake
# apt-get/apt-cache that log their arguments and, when asked to install *-venv, unmount the tmpfs
# (that is what installing the package does). Each scenario runs in a fresh clone of this
# repository. Usage: .ci/fresh-machine.sh [old-ref]   (old-ref: compare with an earlier ./dev)
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
[ "$(id -u)" = 0 ] || { echo "needs root (mount namespace)"; exit 2; }
py=/usr/bin/python3
[ -x "$py" ] || { echo "needs Debian's /usr/bin/python3"; exit 2; }
ver="$("$py" -c 'import sys; print("%d.%d" % sys.version_info[:2])')"
ens="/usr/lib/python$ver/ensurepip"
[ -d "$ens" ] || { echo "$ens not found (is python$ver-venv installed on the host?)"; exit 2; }
work="$(mktemp -d /tmp/probedyn-fresh.XXXXXX)"
mkdir -p "$work/fake"
cat > "$work/fake/apt-get" <<EOF
#!/bin/sh
echo "apt-get \$*" >> $work/apt.log
case "\$*" in *install*-venv*) [ "\${FAKE_APT_FIXES:-1}" = 1 ] && umount $ens 2>/dev/null ;; esac
exit 0
EOF
printf '#!/bin/sh\necho "apt-cache $*" >> %s/apt.log\nexit 0\n' "$work" > "$work/fake/apt-cache"
chmod +x "$work/fake/"*

debian_without_venv() {  # run "$@" as on a machine without python3-venv
  unshare -m bash -c "mount -t tmpfs -o size=1m none $ens && export PATH=$work/fake:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin && \"\$@\"" bash "$@"
}

scenario() {  # name ref [env...] -- command
  local name="$1" ref="$2"; shift 2
  local dir="$work/$name"
  git clone -q "$repo" "$dir"
  git -C "$dir" checkout -q "$ref"
  : > "$work/apt.log"
  echo "=== $name (./dev of $(git -C "$dir" log -1 --format=%h))"
  set +e
  (cd "$dir" && debian_without_venv "$@") > "$work/$name.log" 2>&1
  local rc=$?
  set -e
  grep -v '^WARNING: Location\|^ \|^$\|!!\|^\*\*\*' "$work/$name.log" | tail -6 | sed 's/^/    /'
  echo "    exit $rc; apt calls: $(tr '\n' ';' < "$work/apt.log")"
  echo "    .venv: $([ -e "$dir/.venv" ] && ( [ -x "$dir/.venv/bin/pip" ] && echo complete || echo 'BROKEN (no pip)') || echo absent)"
}

head="$(git -C "$repo" rev-parse HEAD)"
if [ $# -ge 1 ]; then
  scenario old-first "$1" ./dev test -q tests/test_cli_basics.py
  echo "    (second run of the old ./dev after python3-venv is installed:)"
  (cd "$work/old-first" && PATH=/usr/sbin:/usr/bin:/sbin:/bin ./dev test -q tests/test_cli_basics.py 2>&1 | tail -2 | sed 's/^/    /') || true
fi
scenario new-fresh "$head" ./dev test -q tests/test_cli_basics.py
FAKE_APT_FIXES=0 scenario new-apt-does-not-help "$head" ./dev test -q tests/test_cli_basics.py
scenario new-broken-venv "$head" bash -c 'python3 -m venv .venv >/dev/null 2>&1; ./dev test -q tests/test_cli_basics.py'
echo "logs in $work"
