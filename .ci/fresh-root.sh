#!/usr/bin/env bash
# Runs a command inside a brand-new minimal Debian 12 root, the machine a newcomer starts from.
#   bash .ci/fresh-root.sh [--keep] -- COMMAND [ARGS...]
# The root is made with mmdebstrap (minbase variant, packages from the Debian archive); the
# checkout (tracked files plus untracked ones git does not ignore, as they are in the working
# tree) goes to /work/main and ../shared, when present, to /work/shared. COMMAND runs there as
# root, in /work/main, with a clean environment (CI is passed on). Whatever the project forgets
# to install is missing there. The root is removed afterwards unless --keep is given.
# Needs root on the host (mmdebstrap, mount, chroot).
set -euo pipefail
cd "$(dirname "$0")/.."
checkout=$(pwd)
keep=0
while [ $# -gt 0 ]; do
  case "$1" in
    --keep) keep=1; shift ;;
    --) shift; break ;;
    *) echo "fresh-root: unknown option $1 (usage: fresh-root.sh [--keep] -- COMMAND...)" >&2; exit 2 ;;
  esac
done
[ $# -gt 0 ] || { echo "fresh-root: no command given" >&2; exit 2; }
[ "$(id -u)" -eq 0 ] || { echo "fresh-root: needs root (mmdebstrap, mount, chroot)" >&2; exit 1; }

bash .ci/install-deps.sh fresh
parent="${CONFLUENT_FRESH_PARENT:-/var/tmp}"
root=$(mktemp -d "$parent/confluent-fresh.XXXXXX")
mounts=()
cleanup() {
  local status=$?
  for ((i = ${#mounts[@]} - 1; i >= 0; i--)); do
    umount -l "${mounts[$i]}" 2>/dev/null || true
  done
  if [ "$keep" -eq 1 ]; then
    echo "fresh-root: kept $root" >&2
  elif ! grep -q " $root/" /proc/mounts; then
    rm -rf --one-file-system "$root"
  else
    echo "fresh-root: $root still has mounts; not removed" >&2
  fi
  exit $status
}
trap cleanup EXIT
trap 'exit 130' INT TERM

started=$(date +%s)
echo "fresh-root: making a minimal Debian 12 root in $root" >&2
mmdebstrap --quiet --variant=minbase bookworm "$root"
echo "fresh-root: root made in $(( $(date +%s) - started )) s" >&2

mkdir -p "$root/work/main"
git ls-files -z --cached --others --exclude-standard |
  (cd "$checkout" && tar --null --no-recursion -T - -cf -) | tar -xf - -C "$root/work/main"
if [ -d "$checkout/.git" ]; then  # ./dev and the tests may ask git for the commit
  cp -a "$checkout/.git" "$root/work/main/.git"
fi
if [ -d "$checkout/../shared" ]; then
  cp -a "$checkout/../shared" "$root/work/shared"
fi

mount_in_root() {  # TYPE SOURCE TARGET-INSIDE-ROOT
  mkdir -p "$root$3"
  mount -t "$1" "$2" "$root$3"
  mounts+=("$root$3")
}
mount_in_root proc proc /proc
mount_in_root sysfs sysfs /sys
mount_in_root devpts devpts /dev/pts
mount_in_root tmpfs tmpfs /dev/shm
for node in null zero full random urandom tty; do  # mmdebstrap makes these; check, not assume
  [ -e "$root/dev/$node" ] || { echo "fresh-root: $root/dev/$node missing" >&2; exit 1; }
done
cp /etc/resolv.conf "$root/etc/resolv.conf"
# The host's own certificate authorities (a TLS-inspecting proxy's, for example) belong to the
# machine, not to the project: without them npm (export/player's three.js) cannot reach the
# registry from the root. Debian's ca-certificates adds them to the root's store when
# .ci/install-deps.sh installs it, and NODE_EXTRA_CA_CERTS points node at that store.
if compgen -G "/usr/local/share/ca-certificates/*.crt" >/dev/null; then
  mkdir -p "$root/usr/local/share/ca-certificates"
  cp /usr/local/share/ca-certificates/*.crt "$root/usr/local/share/ca-certificates/"
fi

chroot "$root" /usr/bin/env -i HOME=/root LANG=C.UTF-8 TERM=dumb CI="${CI:-}" \
  NODE_EXTRA_CA_CERTS=/etc/ssl/certs/ca-certificates.crt \
  PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
  /bin/bash -c 'cd /work/main && exec "$@"' fresh-root "$@"
