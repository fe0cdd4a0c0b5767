#!/usr/bin/env bash
# The .deb from cpack, checked the way a flight computer would take it:
#   package_test.sh BUILD_DIR WORK_DIR VERSION DEB_ARCH
# builds the package (cpack, the build's CPackConfig.cmake), unpacks it with dpkg-deb -x into a scratch
# root, checks the file list, runs the unpacked qnavd (--version, --check-config on the packaged
# configurations, and a refusal of a file that is no configuration), and checks the control fields
# and the maintainer scripts. Exit 0 pass, 1 fail (every failure printed), 77 skip (no dpkg-deb).
# Cross packages (arm64, armhf; test/package/CMakeLists.txt): the programs run under
# QNAV_PACKAGE_EMULATOR (the toolchain's run-emulator with the target sysroot), every library they
# need (ELF NEEDED) must come from a package in Depends, and QNAV_PACKAGE_SKIP set is a skip with
# that reason (the build has no target daemon: no sysroot).
set -u
BUILD=$1 WORK=$2 VERSION=$3 ARCH=$4
EMU=${QNAV_PACKAGE_EMULATOR:-}
[ -z "${QNAV_PACKAGE_SKIP:-}" ] || { echo "SKIP: $QNAV_PACKAGE_SKIP"; exit 77; }
command -v dpkg-deb >/dev/null || { echo "SKIP: no dpkg-deb on this machine"; exit 77; }
run() { $EMU "$@"; }  # EMU unquoted: the emulator and its arguments (empty for the host package)
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
mark=0
ok() { [ $fails -eq $mark ] && echo "ok: $*"; mark=$fails; }  # "ok" only when its section failed nothing

rm -rf "$WORK" && mkdir -p "$WORK"
if ! cpack --config "$BUILD/CPackConfig.cmake" -B "$WORK/out" >"$WORK/cpack.log" 2>&1; then
  cat "$WORK/cpack.log"; echo "FAIL: cpack"; exit 1
fi
debs=("$WORK"/out/*.deb)
[ ${#debs[@]} -eq 1 ] && [ -f "${debs[0]}" ] || { ls -l "$WORK/out"; echo "FAIL: expected one .deb"; exit 1; }
deb=${debs[0]}
[ "$(basename "$deb")" = "qnav_${VERSION}_${ARCH}.deb" ] || fail "file name $(basename "$deb"), expected qnav_${VERSION}_${ARCH}.deb"
echo "package: $(basename "$deb"), $(stat -c %s "$deb") bytes"

root=$WORK/root
dpkg-deb -x "$deb" "$root" || { echo "FAIL: dpkg-deb -x"; exit 1; }
dpkg-deb -e "$deb" "$WORK/control" || { echo "FAIL: dpkg-deb -e"; exit 1; }

# The file list: everything the install promises, and nothing else at the top.
for f in usr/bin/qnavd usr/bin/qnavd-sim usr/bin/qnav; do
  [ -f "$root/$f" ] && [ -x "$root/$f" ] || fail "$f missing or not executable"
done
for f in usr/lib/systemd/system/qnavd.service etc/qnav/qnavd.toml usr/share/qnav/examples/vehicle.toml \
         usr/share/qnav/examples/sim.toml usr/share/qnav/qnav.dbc usr/share/man/man1/qnavd.1.gz \
         usr/share/man/man1/qnavd-sim.1.gz usr/share/man/man1/qnav.1.gz usr/share/doc/qnav/qnavd.md usr/share/doc/qnav/install.md; do
  [ -f "$root/$f" ] || fail "$f missing"
done
top=$(cd "$root" && ls -A | tr '\n' ' ')
[ "$top" = "etc usr " ] || fail "top-level entries '$top', expected 'etc usr '"
stray=$(cd "$root" && find . -name '*.a' -o -name '*.h' -o -name '*.hpp' -o -name '*.cmake' | head -5)
[ -z "$stray" ] || fail "build or development files in the package: $stray"
# The unit starts what the package holds.
exec_path=$(sed -n 's/^ExecStart=\([^ ]*\).*/\1/p' "$root/usr/lib/systemd/system/qnavd.service")
conf_path=$(sed -n 's/^ExecStart=.*--config \([^ ]*\).*/\1/p' "$root/usr/lib/systemd/system/qnavd.service")
[ -n "$exec_path" ] && [ -x "$root$exec_path" ] || fail "the unit's ExecStart '$exec_path' is not in the package"
[ -n "$conf_path" ] && [ -f "$root$conf_path" ] || fail "the unit's configuration '$conf_path' is not in the package"
for m in qnavd qnav; do
  page=$(gzip -dc "$root/usr/share/man/man1/$m.1.gz" 2>/dev/null) || fail "$m.1.gz is not gzip"
  echo "$page" | grep -q "^\.TH ${m^^} 1" || fail "$m.1.gz has no .TH header"
done
gzip -dc "$root/usr/share/man/man1/qnavd.1.gz" | grep -q -- "--check-config" || fail "qnavd.1 lacks the --help text"
# The flight binary links no image-file library (the simulator and the tools' PNG/JPEG are in qnavd-sim and qnav).
needed=$(readelf -d "$root/usr/bin/qnavd" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p' | tr '\n' ' ')
case "$needed" in *libpng*|*libjpeg*) fail "the flight binary qnavd loads an image library: $needed" ;; esac
ok "file list ($(cd "$root" && find . -type f | wc -l) files)"

# The unpacked programs run.
qnavd=$root/usr/bin/qnavd
out=$(run "$qnavd" --version 2>&1); rc=$?
[ $rc -eq 0 ] && [ "$out" = "qnavd $VERSION" ] || fail "qnavd --version: exit $rc, '$out' (expected 'qnavd $VERSION')"
for c in usr/share/qnav/examples/sim.toml usr/share/qnav/examples/vehicle.toml etc/qnav/qnavd.toml; do
  out=$(run "$qnavd" --check-config "$root/$c" 2>&1); rc=$?
  [ $rc -eq 0 ] && [ "$out" = "$root/$c: valid" ] || fail "qnavd --check-config $c: exit $rc, '$out'"
done
out=$(run "$qnavd" --check-config "$root/usr/share/qnav/qnav.dbc" 2>&1); rc=$?
[ $rc -ne 0 ] || fail "qnavd --check-config accepted qnav.dbc: '$out'"
out=$(run "$root/usr/bin/qnav" version 2>&1); rc=$?
[ $rc -eq 0 ] && echo "$out" | grep -q "$VERSION" || fail "qnav version: exit $rc, '$out'"
ok "unpacked qnavd${EMU:+ (under $(basename "${EMU%% *}"))} --version, --check-config on 3 configurations, refusal of a DBC; qnav version"

# The control file and the maintainer scripts.
field() { dpkg-deb -f "$deb" "$1"; }
[ "$(field Package)" = qnav ] || fail "Package '$(field Package)'"
[ "$(field Version)" = "$VERSION" ] || fail "Version '$(field Version)'"
[ "$(field Architecture)" = "$ARCH" ] || fail "Architecture '$(field Architecture)', expected $ARCH"
deps=$(field Depends)
[ -n "$deps" ] || fail "Depends empty"
for d in libc6 adduser; do echo "$deps" | grep -qw "$d" || fail "Depends lacks $d: '$deps'"; done
# Cross packages: Depends is a fixed list (no dpkg-shlibdeps for the target), so every shared library
# the programs load must map to a package of that list, and the ELF machine must be the package's.
if [ -n "$EMU" ]; then
  case $ARCH in arm64) machine=AArch64 ;; armhf) machine=ARM ;; *) machine=? ;; esac
  for p in qnavd qnavd-sim qnav; do
    readelf -h "$root/usr/bin/$p" | grep -q "Machine: *$machine" || fail "$p is not an $ARCH ($machine) program"
    for lib in $(readelf -d "$root/usr/bin/$p" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
      case $lib in
        libc.so.6|libm.so.6|ld-linux-*) pkg=libc6 ;;
        libstdc++.so.6) pkg=libstdc++6 ;;
        libgcc_s.so.1) pkg=libgcc-s1 ;;
        libgpiod.so.2) pkg=libgpiod2 ;;
        libpng16.so.16) pkg=libpng16-16 ;;
        libjpeg.so.62) pkg=libjpeg62-turbo ;;
        libz.so.1) pkg=zlib1g ;;
        *) fail "$p needs $lib, which no Depends entry is known to provide"; continue ;;
      esac
      echo "$deps" | tr ',' '\n' | awk '{print $1}' | grep -qxF "$pkg" || fail "$p needs $lib ($pkg), not in Depends: '$deps'"
    done
  done
  ok "NEEDED of qnavd, qnav ($machine): $(readelf -d "$root/usr/bin/qnavd" "$root/usr/bin/qnav" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p' | sort -u | tr '\n' ' ')all in Depends"
fi
for s in postinst prerm postrm; do
  [ -f "$WORK/control/$s" ] && [ -x "$WORK/control/$s" ] || { fail "$s missing or not executable"; continue; }
  sh -n "$WORK/control/$s" || fail "$s: sh -n"
done
sed 's/#.*//' "$WORK/control/postinst" | grep -Eq 'systemctl.*(enable|[[:space:]]start)|deb-systemd-invoke start' &&
  fail "postinst enables or starts the service"
grep -q 'adduser --system' "$WORK/control/postinst" || fail "postinst does not create the system user"
grep -qx /etc/qnav/qnavd.toml "$WORK/control/conffiles" 2>/dev/null || fail "/etc/qnav/qnavd.toml is not a conffile"
ok "control: Package $(field Package), Version $(field Version), Architecture $(field Architecture), Depends: $deps"

[ $fails -eq 0 ] || { echo "qnav_package_deb: $fails failure(s)"; exit 1; }
echo "qnav_package_deb: pass"
