#!/bin/sh
# Run lcm-spy with the cblox LCM types so it can decode the CBLOX_* channels.
#
# Usage: scripts/lcm-spy.sh [path/to/cblox_lcmtypes.jar] [lcm-spy args...]
#   The jar defaults to build/lcmtypes/cblox_lcmtypes.jar (built by the
#   cblox_lcmtypes_jar target when a JDK is installed).
#
# Needs: liblcm-bin + liblcm-java (lcm-spy, lcm.jar), openjdk-17-jre (or any
# Java runtime) and libjchart2d-java (/usr/share/java/jchart2d.jar).
#   sudo apt-get install liblcm-bin liblcm-java openjdk-17-jre libjchart2d-java
#
# lcm-spy discovers message classes through the CLASSPATH environment
# variable. The stock launcher passes JVM options that newer JDKs reject
# (e.g. -Xincgc), so we tell the JVM to ignore unrecognised options.
set -eu

script_dir=$(cd "$(dirname "$0")" && pwd)
default_jar="$script_dir/../build/lcmtypes/cblox_lcmtypes.jar"

jar="$default_jar"
if [ $# -gt 0 ]; then
  case "$1" in
    *.jar) jar="$1"; shift ;;
  esac
fi

if [ ! -f "$jar" ]; then
  echo "lcm-spy.sh: jar not found: $jar" >&2
  echo "  build it with: cmake --build build --target cblox_lcmtypes_jar" >&2
  exit 1
fi

lcm_jar=/usr/share/java/lcm.jar
jchart_jar=/usr/share/java/jchart2d.jar
for f in "$lcm_jar" "$jchart_jar"; do
  [ -f "$f" ] || echo "lcm-spy.sh: warning: $f missing (install liblcm-java / libjchart2d-java)" >&2
done

CLASSPATH="$jar:$lcm_jar:$jchart_jar${CLASSPATH:+:$CLASSPATH}"
export CLASSPATH
JDK_JAVA_OPTIONS=-XX:+IgnoreUnrecognizedVMOptions
export JDK_JAVA_OPTIONS

exec lcm-spy "$@"
