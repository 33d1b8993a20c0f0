#!/usr/bin/env bash
# Runs lcm-spy with the cblox LCM types, so it decodes the CBLOX_* channels (type, rate,
# bandwidth per channel; double-click a channel to see its fields).
#
# Usage: scripts/lcm-spy.sh [--check] [path/to/cblox_lcmtypes.jar] [lcm-spy args...]
#   scripts/lcm-spy.sh                                     # LCM's default URL, as the daemons
#   scripts/lcm-spy.sh --lcm-url 'udpm://239.255.76.67:7667?ttl=0'
#   scripts/netns-run.sh scripts/lcm-spy.sh                # inside a private network namespace
#   --check  only check that everything is installed and built (exit 0), or say what is
#            missing (exit 1); nothing is started and no X display is needed.
# The jar defaults to ${BUILD_DIR:-build}/lcmtypes/cblox_lcmtypes.jar (CMake target
# cblox_lcmtypes_jar, built with the rest by scripts/build.sh); if it is missing but that
# build folder is configured, it is built first; with no build folder, the installed
# <prefix>/share/java/cblox_lcmtypes.jar (/usr or /usr/local) is used.
#
# Needs (Debian 12; all in scripts/setup.sh): liblcm-bin (lcm-spy), liblcm-java (lcm.jar),
# libjchart2d-java (jchart2d.jar, lcm-spy's charts), openjdk-17-jre (a JRE with AWT/X11:
# the -headless JRE cannot open a window), and an X display (DISPLAY: a desktop session,
# ssh -X, or xvfb-run from packages xvfb and xauth).
#
# lcm-spy finds message classes by scanning the jars on the CLASSPATH environment variable.
# Its launcher passes JVM options that JDK 17 rejects (-Xincgc), so we tell the JVM to
# ignore unrecognised options; JDK_JAVA_OPTIONS given by the caller are kept.
# Exit status: lcm-spy's; 1 when something is missing (the message names the package).
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${BUILD_DIR:-build}
[[ "$build_dir" = /* ]] || build_dir="$repo/$build_dir"

check_only=0
if [[ "${1:-}" == "--check" ]]; then
  check_only=1
  shift
fi
jar="$build_dir/lcmtypes/cblox_lcmtypes.jar"
jar_given=0
if [[ $# -gt 0 && "$1" == *.jar ]]; then
  jar="$1"
  jar_given=1
  shift
fi

lcm_jar=/usr/share/java/lcm.jar
jchart_jar=/usr/share/java/jchart2d.jar

# What is missing, as "what (package)", and the packages to install.
missing=()
packages=()
need() {  # need PACKAGE WHAT
  missing+=("$2 (package $1)")
  [[ " ${packages[*]-} " == *" $1 "* ]] || packages+=("$1")
}
command -v lcm-spy > /dev/null || need liblcm-bin "the lcm-spy command"
[[ -f "$lcm_jar" ]] || need liblcm-java "$lcm_jar"
[[ -f "$jchart_jar" ]] || need libjchart2d-java "$jchart_jar"
if ! java_bin=$(command -v java); then
  need openjdk-17-jre "a Java runtime (java)"
else
  # A JRE that can open windows ships libawt_xawt.so; the -headless packages do not.
  java_home=$(dirname "$(dirname "$(readlink -f "$java_bin")")")
  [[ -f "$java_home/lib/libawt_xawt.so" ]] ||
    need openjdk-17-jre "a Java runtime with AWT/X11 ($java_home is headless)"
fi
if [[ ${#missing[@]} -gt 0 ]]; then
  echo "lcm-spy.sh: missing:" >&2
  for m in "${missing[@]}"; do echo "  $m" >&2; done
  echo "  install with: sudo apt-get install ${packages[*]}" >&2
  echo "  (or: sudo bash scripts/setup.sh, which installs everything cblox needs)" >&2
  exit 1
fi

if [[ ! -f "$jar" && $jar_given -eq 0 ]]; then
  if [[ -f "$build_dir/CMakeCache.txt" ]]; then
    echo "lcm-spy.sh: building $jar" >&2
    cmake --build "$build_dir" --target cblox_lcmtypes_jar >&2 || true
  fi
  # Not built here: the jar that `cmake --install` / the Debian package put in place.
  for installed in /usr/share/java/cblox_lcmtypes.jar /usr/local/share/java/cblox_lcmtypes.jar; do
    if [[ ! -f "$jar" && -f "$installed" ]]; then jar=$installed; fi
  done
fi
if [[ ! -f "$jar" ]]; then
  echo "lcm-spy.sh: jar of the cblox LCM types not found: $jar" >&2
  echo "  build it with: bash scripts/build.sh   (or: cmake --build build --target cblox_lcmtypes_jar;" >&2
  echo "  the target exists when CMake found javac: package default-jdk-headless)" >&2
  exit 1
fi

if [[ $check_only -eq 1 ]]; then
  echo "lcm-spy.sh: ready (types: $jar)"
  exit 0
fi
if [[ -z "${DISPLAY:-}" ]]; then
  echo "lcm-spy.sh: no X display (DISPLAY is empty): run it in a desktop session, over" >&2
  echo "  ssh -X, or headless under Xvfb: xvfb-run -a scripts/lcm-spy.sh (packages xvfb, xauth)" >&2
  exit 1
fi

CLASSPATH="$jar:$lcm_jar:$jchart_jar${CLASSPATH:+:$CLASSPATH}"
export CLASSPATH
JDK_JAVA_OPTIONS="-XX:+IgnoreUnrecognizedVMOptions${JDK_JAVA_OPTIONS:+ $JDK_JAVA_OPTIONS}"
export JDK_JAVA_OPTIONS

exec lcm-spy "$@"
