#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# /init of the kernel-test VM (tests/integration/init.sh; run-vm.sh copies it
# into the initramfs). Mounts the pseudo file systems, makes vcan0 and a
# gpio-sim chip, runs every program in /tests, and ends QEMU through
# isa-debug-exit (kt_exit): 0 = all passed, 1 = a failure.
# Kernel command line: trn.shell=1 gives a shell instead (debugging).
export PATH=/bin:/sbin:/usr/bin:/usr/sbin
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
mount -t configfs configfs /sys/kernel/config
mount -t tmpfs tmpfs /tmp

fail() {
  echo "KT-SETUP-FAILED $*"
  echo "KT-DONE fail"
  /bin/kt_exit 1
  exit 1
}

echo "KT-BOOT $(uname -r)"
ip link add dev vcan0 type vcan || fail "ip link add vcan0"
ip link set dev vcan0 up || fail "ip link set vcan0 up"
export TRN_CAN_IF=vcan0

g=/sys/kernel/config/gpio-sim/trn
mkdir "$g" "$g/bank0" || fail "gpio-sim configfs (CONFIG_GPIO_SIM?)"
echo 8 >"$g/bank0/num_lines" || fail "gpio-sim num_lines"
echo trn-sim >"$g/bank0/label" || fail "gpio-sim label"
echo 1 >"$g/live" || fail "gpio-sim live"
TRN_GPIO_CHIP=$(cat "$g/bank0/chip_name")
TRN_GPIO_SIM=/sys/devices/platform/$(cat "$g/dev_name")/$TRN_GPIO_CHIP
export TRN_GPIO_CHIP TRN_GPIO_SIM
[ -d "$TRN_GPIO_SIM/sim_gpio0" ] || fail "no $TRN_GPIO_SIM/sim_gpio0"
echo "KT-SETUP vcan0 $TRN_GPIO_CHIP $TRN_GPIO_SIM"

if grep -q 'trn.shell=1' /proc/cmdline; then
  echo "KT-SHELL (exit the shell to end the VM)"
  sh
  /bin/kt_exit 1
fi

status=pass
for t in /tests/*; do
  [ -x "$t" ] || continue
  name=$(basename "$t")
  echo "KT-RUN $name"
  "$t"
  rc=$?
  echo "KT-EXIT $name $rc"
  [ "$rc" -eq 0 ] || status=fail
done
echo "KT-DONE $status"
if [ "$status" = pass ]; then
  /bin/kt_exit 0
else
  /bin/kt_exit 1
fi
