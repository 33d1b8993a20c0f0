# Sourced by build.sh, tsan.sh and fuzz.sh from the repository's root: ccache keys its
# results on paths relative to the checkout (base_dir) and not on the build directory
# (hash_dir off), so a clone in another folder (CI clones the submission afresh) reuses the
# objects compiled here instead of rebuilding cold. Set either variable to override.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
export CCACHE_NOHASHDIR="${CCACHE_NOHASHDIR:-true}"
