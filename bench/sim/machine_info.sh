#!/bin/sh
# The machine a device bench ran on, for its results folder: date, kernel, core count, lscpu, the
# CPU model and flags, clock readings and the frequency governor.
date -u '+%Y-%m-%d %H:%M:%S UTC'
uname -a
echo "nproc $(nproc)"
lscpu 2>/dev/null
grep -m1 'model name' /proc/cpuinfo
grep -m1 '^flags' /proc/cpuinfo
grep MHz /proc/cpuinfo | sort | uniq -c | head -5
cat /sys/devices/system/cpu/cpu0/cpufreq/scaling_governor 2>/dev/null
