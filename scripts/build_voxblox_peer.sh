#!/usr/bin/env bash
# Builds the prefix the voxblox benchmark peer links (cblox-bench-integrators, see
# test/bench/CMakeLists.txt: -DCBLOX_VOXBLOX_ROOT=PREFIX) from source checkouts of voxblox and
# minkindr made beforehand: this script downloads nothing. It runs protoc on
# voxblox/proto/voxblox/*.proto, compiles voxblox/src/**/*.cc and the two .pb.cc with g++
# (-O3 -DNDEBUG -std=c++17 -fPIC, Eigen from /usr/include/eigen3, Debian's glog and protobuf)
# at most JOBS at a time under nice, and installs into PREFIX:
#   include/voxblox/...        voxblox/include/voxblox, plus the generated Block.pb.h, Layer.pb.h
#   include/kindr/minimal/...  minkindr/include/kindr
#   lib/libvoxblox.a           every object that compiled, the .pb.o included (no separate
#                              libvoxblox_proto: an old one in PREFIX is removed)
#   share/voxblox-peer/build-info.txt  sources, commits (when the checkouts are git work
#                              trees), compiler and flags
# The sources the benchmark's peer and voxblox's TSDF/ESDF integrators need must compile
# (core/block, integrator/{integrator_utils,tsdf_integrator,esdf_integrator,
# esdf_occ_integrator}, utils/{protobuf_utils,timing,voxel_utils,neighbor_tools}, the .pb.cc);
# any other voxblox source that fails is reported and left out of the library.
# Known good: ethz-asl/voxblox c8066b04075d, ethz-asl/minkindr 564f12639a84.
#
# Usage: scripts/build_voxblox_peer.sh --voxblox DIR --minkindr DIR --prefix PREFIX
#                                      [--jobs N (2)] [--build-dir DIR] [--core]
#                                      [--cxxflags "FLAGS"]
#   --voxblox DIR    checkout of ethz-asl/voxblox (git work tree or `git archive` extraction):
#                    its root (holding voxblox/) or the voxblox/ package itself
#   --minkindr DIR   checkout of ethz-asl/minkindr: its root (holding minkindr/) or the
#                    minkindr/ package itself
#   --prefix PREFIX  where to install (created; its include/voxblox, include/kindr and
#                    lib/libvoxblox*.a are replaced)
#   --jobs N         parallel compiles (default 2)
#   --build-dir DIR  keep objects, generated code and compiler logs there (default: a
#                    temporary directory, removed at the end)
#   --core           compile only the required sources above (plus core/esdf_map and
#                    core/tsdf_map), not all of voxblox/src
#   --cxxflags FLAGS extra compiler flags, e.g. "-march=native" to match a cblox build
#                    configured with CBLOX_NATIVE=ON (Eigen's alignment must agree)
# Needs g++, protoc and the headers of Eigen, glog and protobuf (Debian: g++ libeigen3-dev
# libgoogle-glog-dev libprotobuf-dev protobuf-compiler; scripts/setup.sh --bench).
# Exit status: 0 done, 1 a dependency is missing or a required source failed, 2 usage.
set -euo pipefail

usage() { sed -n '2,38p' "$0" | sed 's/^# \{0,1\}//'; }
voxblox_dir="" minkindr_dir="" prefix="" jobs=2 build_dir="" core=0 extra_flags=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --voxblox) voxblox_dir=${2:?}; shift 2 ;;
    --minkindr) minkindr_dir=${2:?}; shift 2 ;;
    --prefix) prefix=${2:?}; shift 2 ;;
    --jobs) jobs=${2:?}; shift 2 ;;
    --build-dir) build_dir=${2:?}; shift 2 ;;
    --core) core=1; shift ;;
    --cxxflags) extra_flags=${2?}; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "build_voxblox_peer: unknown argument '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
if [[ -z $voxblox_dir || -z $minkindr_dir || -z $prefix ]]; then
  echo "build_voxblox_peer: --voxblox, --minkindr and --prefix are required" >&2
  usage >&2
  exit 2
fi
if ! [[ $jobs =~ ^[1-9][0-9]*$ ]]; then
  echo "build_voxblox_peer: --jobs wants a positive number, not '$jobs'" >&2
  exit 2
fi

log() { echo "build_voxblox_peer: $*"; }
die() { echo "build_voxblox_peer: $*" >&2; exit 1; }

# The packages inside the checkouts: the repository root or the package directory itself.
if [[ -f $voxblox_dir/voxblox/include/voxblox/core/block.h ]]; then
  voxblox_pkg=$voxblox_dir/voxblox
elif [[ -f $voxblox_dir/include/voxblox/core/block.h ]]; then
  voxblox_pkg=$voxblox_dir
else
  die "no voxblox sources in '$voxblox_dir' (expected voxblox/include/voxblox/core/block.h)"
fi
if [[ -f $minkindr_dir/minkindr/include/kindr/minimal/quat-transformation.h ]]; then
  minkindr_pkg=$minkindr_dir/minkindr
elif [[ -f $minkindr_dir/include/kindr/minimal/quat-transformation.h ]]; then
  minkindr_pkg=$minkindr_dir
else
  die "no minkindr sources in '$minkindr_dir' (expected" \
    "minkindr/include/kindr/minimal/quat-transformation.h)"
fi
voxblox_pkg=$(cd "$voxblox_pkg" && pwd)
minkindr_pkg=$(cd "$minkindr_pkg" && pwd)
[[ -d $voxblox_pkg/src && -d $voxblox_pkg/proto/voxblox ]] ||
  die "'$voxblox_pkg' has no src/ or proto/voxblox/"

# Debian's toolchain and libraries.
missing=()
command -v g++ >/dev/null || missing+=(g++)
command -v protoc >/dev/null || missing+=(protobuf-compiler)
[[ -f /usr/include/eigen3/Eigen/Core ]] || missing+=(libeigen3-dev)
[[ -f /usr/include/glog/logging.h ]] || missing+=(libgoogle-glog-dev)
[[ -f /usr/include/google/protobuf/message.h ]] || missing+=(libprotobuf-dev)
if [[ ${#missing[@]} -gt 0 ]]; then
  die "missing: ${missing[*]} (apt-get install ${missing[*]}, or scripts/setup.sh --bench)"
fi

# Sources: these must compile, the rest of voxblox/src may fail (reported, left out).
required=(
  core/block.cc
  integrator/integrator_utils.cc
  integrator/tsdf_integrator.cc
  integrator/esdf_integrator.cc
  integrator/esdf_occ_integrator.cc
  utils/protobuf_utils.cc
  utils/timing.cc
  utils/voxel_utils.cc
)
[[ -f $voxblox_pkg/src/utils/neighbor_tools.cc ]] && required+=(utils/neighbor_tools.cc)
for source in "${required[@]}"; do
  [[ -f $voxblox_pkg/src/$source ]] || die "'$voxblox_pkg/src/$source' is missing"
done
optional=()
if [[ $core == 1 ]]; then
  for source in core/esdf_map.cc core/tsdf_map.cc; do
    [[ -f $voxblox_pkg/src/$source ]] && optional+=("$source")
  done
else
  while IFS= read -r source; do
    [[ " ${required[*]} " == *" $source "* ]] || optional+=("$source")
  done < <(cd "$voxblox_pkg/src" && find . -name '*.cc' | sed 's|^\./||' | LC_ALL=C sort)
fi

if [[ -z $build_dir ]]; then
  build_dir=$(mktemp -d "${TMPDIR:-/tmp}/voxblox-peer-build.XXXXXX")
  trap 'rm -rf "$build_dir"' EXIT
else
  mkdir -p "$build_dir"
  build_dir=$(cd "$build_dir" && pwd)
  rm -rf "$build_dir/gen" "$build_dir/obj" "$build_dir/logs"
fi
mkdir -p "$build_dir/gen" "$build_dir/obj" "$build_dir/logs"
start=$SECONDS

# The commit of a checkout (package directory PKG) when it is a git work tree of its own, not
# an extraction that happens to lie inside some other repository.
commit_of() {
  local top
  top=$(git -C "$1" rev-parse --show-toplevel 2>/dev/null) || top=""
  if [[ -n $top && ($top == "$1" || $top == "$(dirname "$1")") ]]; then
    git -C "$1" rev-parse HEAD
  else
    echo "unknown (not a git work tree)"
  fi
}
log "voxblox:  $voxblox_pkg (commit $(commit_of "$voxblox_pkg"))"
log "minkindr: $minkindr_pkg (commit $(commit_of "$minkindr_pkg"))"
log "prefix:   $prefix; build directory $build_dir; $jobs job(s)"

# protoc: voxblox/Block.pb.{h,cc}, voxblox/Layer.pb.{h,cc}, included as "voxblox/Block.pb.h".
protos=()
while IFS= read -r proto; do protos+=("$proto"); done < <(
  cd "$voxblox_pkg/proto" && find voxblox -name '*.proto' | LC_ALL=C sort)
[[ ${#protos[@]} -gt 0 ]] || die "no .proto in '$voxblox_pkg/proto/voxblox'"
log "protoc $(protoc --version | sed 's/^libprotoc //'): ${protos[*]}"
(cd "$voxblox_pkg/proto" && protoc -I. --cpp_out="$build_dir/gen" "${protos[@]}")
pb_sources=()
for proto in "${protos[@]}"; do pb_sources+=("pb:${proto%.proto}.pb.cc"); done

cxxflags="-O3 -DNDEBUG -std=c++17 -fPIC${extra_flags:+ $extra_flags}"
includes="-I$voxblox_pkg/include -I$build_dir/gen -I$minkindr_pkg/include -I/usr/include/eigen3"
log "g++ $(g++ -dumpfullversion) $cxxflags"

# One compile: SOURCE is "pb:voxblox/X.pb.cc" (generated) or a path under voxblox/src.
# Leaves obj/NAME.o on success, logs/NAME.log (the compiler's output) either way; NAME is
# the path with '/' as '-' (core-block, proto-Block.pb): ar keeps only a member's base name.
compile_one() {
  local source=$1 path name
  if [[ $source == pb:* ]]; then
    path=$BUILD_DIR/gen/${source#pb:}
    name=proto-$(basename "${source#pb:}" .cc)
  else
    path=$VOXBLOX_PKG/src/$source
    name=${source%.cc}
    name=${name//\//-}
  fi
  local t0=$SECONDS
  # shellcheck disable=SC2086  # the flags are word lists
  if nice -n 10 g++ $CXXFLAGS $INCLUDES -c "$path" -o "$BUILD_DIR/obj/$name.o.tmp" \
      >"$BUILD_DIR/logs/$name.log" 2>&1; then
    mv "$BUILD_DIR/obj/$name.o.tmp" "$BUILD_DIR/obj/$name.o"
    local warnings
    warnings=$(grep -c 'warning:' "$BUILD_DIR/logs/$name.log" || true)
    echo "build_voxblox_peer:   compiled ${source#pb:} ($((SECONDS - t0)) s$(
      [[ $warnings -gt 0 ]] && echo ", $warnings warning(s)"))"
  else
    rm -f "$BUILD_DIR/obj/$name.o.tmp"
    echo "build_voxblox_peer:   FAILED   ${source#pb:} ($((SECONDS - t0)) s)"
  fi
  return 0
}
export -f compile_one
export BUILD_DIR=$build_dir VOXBLOX_PKG=$voxblox_pkg CXXFLAGS=$cxxflags INCLUDES=$includes

all=("${pb_sources[@]}" "${required[@]}" "${optional[@]}")
log "compiling ${#all[@]} sources ($((${#required[@]} + ${#pb_sources[@]})) required," \
  "${#optional[@]} optional)"
# shellcheck disable=SC2016  # $1 is expanded by the inner bash
printf '%s\n' "${all[@]}" | xargs -d '\n' -P "$jobs" -n 1 bash -c 'compile_one "$1"' _

name_of() {
  if [[ $1 == pb:* ]]; then
    echo "proto-$(basename "${1#pb:}" .cc)"
  else
    local name=${1%.cc}
    echo "${name//\//-}"
  fi
}
object_of() { echo "$build_dir/obj/$(name_of "$1").o"; }
log_of() { echo "$build_dir/logs/$(name_of "$1").log"; }
failed_required=() failed_optional=() objects=() compiled=()
for source in "${pb_sources[@]}" "${required[@]}"; do
  if [[ -f $(object_of "$source") ]]; then
    objects+=("$(object_of "$source")"); compiled+=("${source#pb:}")
  else
    failed_required+=("$source")
  fi
done
for source in "${optional[@]}"; do
  if [[ -f $(object_of "$source") ]]; then
    objects+=("$(object_of "$source")"); compiled+=("$source")
  else
    failed_optional+=("$source")
  fi
done
for source in "${failed_optional[@]}"; do
  echo "build_voxblox_peer: optional source ${source} did not compile (left out):" >&2
  grep -m 5 'error' "$(log_of "$source")" | sed 's/^/    /' >&2 || true
done
if [[ ${#failed_required[@]} -gt 0 ]]; then
  for source in "${failed_required[@]}"; do
    echo "build_voxblox_peer: required source ${source#pb:} did not compile:" >&2
    head -n 30 "$(log_of "$source")" | sed 's/^/    /' >&2
  done
  die "${#failed_required[@]} required source(s) failed; nothing installed"
fi

log "archiving ${#objects[@]} objects into libvoxblox.a"
rm -f "$build_dir/libvoxblox.a"
ar rcs "$build_dir/libvoxblox.a" "${objects[@]}"

log "installing into $prefix"
mkdir -p "$prefix/include" "$prefix/lib" "$prefix/share/voxblox-peer"
rm -rf "$prefix/include/voxblox" "$prefix/include/kindr"
rm -f "$prefix/lib/libvoxblox.a" "$prefix/lib/libvoxblox.so" "$prefix/lib/libvoxblox_proto.a" \
  "$prefix/lib/libvoxblox_proto.so"
cp -R "$voxblox_pkg/include/voxblox" "$prefix/include/voxblox"
cp "$build_dir"/gen/voxblox/*.pb.h "$prefix/include/voxblox/"
cp -R "$minkindr_pkg/include/kindr" "$prefix/include/kindr"
cp "$build_dir/libvoxblox.a" "$prefix/lib/libvoxblox.a"
{
  echo "voxblox: $voxblox_pkg"
  echo "voxblox commit: $(commit_of "$voxblox_pkg")"
  echo "minkindr: $minkindr_pkg"
  echo "minkindr commit: $(commit_of "$minkindr_pkg")"
  echo "compiler: g++ $(g++ -dumpfullversion)"
  echo "flags: $cxxflags"
  echo "protoc: $(protoc --version)"
  echo "compiled:"
  printf '  %s\n' "${compiled[@]}"
  if [[ ${#failed_optional[@]} -gt 0 ]]; then
    echo "left out (did not compile):"
    printf '  %s\n' "${failed_optional[@]}"
  fi
} >"$prefix/share/voxblox-peer/build-info.txt"

log "done in $((SECONDS - start)) s: ${#compiled[@]} sources in $prefix/lib/libvoxblox.a$(
  [[ ${#failed_optional[@]} -gt 0 ]] && echo " (${#failed_optional[@]} optional left out)")"
log "configure cblox with -DCBLOX_VOXBLOX_ROOT=$prefix"
