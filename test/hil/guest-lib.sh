# test/hil/guest-lib.sh: helpers for a scenario's guest script (bash, in the bench guest), sourced as
#   . "$QNAV_HIL_DIR/../../guest-lib.sh"
#  hil_skip REASON...             the scenario cannot run here: writes skip.txt, prints
#                                  `hil guest: SKIP: REASON`, exits 77 (run-scenario reports a skip)
#  hil_vivid_load [PARAM=VALUE...] loads vivid (shipped in the initramfs, test/hil/init copies it to
#                                  /run/qnav-hil/modules) with its parameters and waits for its nodes
#  hil_vivid_unload                removes vivid (every file handle on it must be closed)
#  hil_gpio_sim_chip NAME LINES    makes a gpio-sim chip of LINES lines through configfs and sets
#                                  HIL_GPIO_CHIP (/dev/gpiochipN), HIL_GPIO_SYSFS (its sim_gpioK folder's
#                                  parent); skips with the reason when gpio-sim is not in this kernel
hil_modules=/run/qnav-hil/modules

hil_skip() {
  echo "$*" > skip.txt
  echo "hil guest: SKIP: $*"
  exit 77
}

hil_vivid_load() {
  [ -f "$hil_modules/vivid.ko" ] || hil_skip "vivid.ko is not in the bench's initramfs ($hil_modules)"
  /bin/busybox insmod "$hil_modules/vivid.ko" "$@" || { echo "guest: insmod vivid.ko $* failed"; return 1; }
  local i
  for i in $(seq 50); do
    ls /dev/video* > /dev/null 2>&1 && return 0
    sleep 0.1
  done
  echo "guest: vivid loaded but no /dev/video* appeared"
  return 1
}

hil_vivid_unload() {
  /bin/busybox rmmod vivid
}

hil_gpio_sim_chip() {
  local name=$1 lines=$2 cfg=/sys/kernel/config/gpio-sim
  if [ ! -d "$cfg" ]; then
    hil_skip "$(cat /run/qnav-hil/gpio-sim.skip 2>/dev/null || echo "gpio-sim is not loaded in the bench kernel ($cfg missing)")"
  fi
  mkdir "$cfg/$name" "$cfg/$name/gpio-bank0" || return 1
  echo "$lines" > "$cfg/$name/gpio-bank0/num_lines" || return 1
  echo 1 > "$cfg/$name/live" || return 1
  HIL_GPIO_CHIP=/dev/$(cat "$cfg/$name/gpio-bank0/chip_name")
  HIL_GPIO_SYSFS=/sys/devices/platform/$(cat "$cfg/$name/dev_name")/$(basename "$HIL_GPIO_CHIP")
  [ -c "$HIL_GPIO_CHIP" ] && [ -d "$HIL_GPIO_SYSFS" ] || { echo "guest: gpio-sim chip $name: no $HIL_GPIO_CHIP or $HIL_GPIO_SYSFS"; return 1; }
  echo "guest: gpio-sim chip $name: $HIL_GPIO_CHIP, $lines lines, $HIL_GPIO_SYSFS"
}
