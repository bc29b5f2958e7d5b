# Sourced by the build scripts (issue 41): where ccache keeps its cache and how it hashes.
# CI builds a fresh clone in another folder each run on the same machine, so the cache lives
# outside the clone (SEMAP_CCACHE_DIR, default ~/.cache/semap-ccache) and paths under the
# clone are hashed relative to it (base_dir; hash_dir off, so the -g1 sanitizer builds hit too).
# CMake compiles through ccache when it is installed (cmake/Ccache.cmake).
if command -v ccache >/dev/null 2>&1; then
  export CCACHE_DIR="${SEMAP_CCACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/semap-ccache}"
  export CCACHE_BASEDIR="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
  export CCACHE_NOHASHDIR=true
  export CCACHE_MAXSIZE="${SEMAP_CCACHE_SIZE:-12G}"
  mkdir -p "$CCACHE_DIR"
fi

# ccache_zero / ccache_report LABEL: the hits and misses of this step's own compilations. The
# cache is shared (other clones and sessions compile through it at the same time), so its global
# counters mix their compilations in; each compilation of this step is instead logged to a file
# of its own (ccache's stats_log, CCACHE_STATSLOG) and counted from there.
ccache_zero() {
  command -v ccache >/dev/null 2>&1 || return 0
  export CCACHE_STATSLOG="${TMPDIR:-/tmp}/semap-ccache-stats.$$.log"
  : >"$CCACHE_STATSLOG"
}
ccache_report() {
  command -v ccache >/dev/null 2>&1 || { echo "semap ccache: $1: ccache not installed"; return 0; }
  [ -f "${CCACHE_STATSLOG:-}" ] || { echo "semap ccache: $1: no compilation logged"; return 0; }
  awk -v label="$1" '
    $1 == "direct_cache_hit" || $1 == "preprocessed_cache_hit" { hit++ }
    $1 == "cache_miss" { miss++ }
    $1 == "could_not_use_precompiled_header" || $1 == "unsupported_compiler_option" { odd++ }
    END { total = hit + miss
          printf "semap ccache: %s: %d of %d compilations from the cache (%.0f %%)%s\n", label, hit, total,
                 total ? 100 * hit / total : 0, odd ? sprintf(", %d not cacheable", odd) : "" }' "$CCACHE_STATSLOG"
  rm -f "$CCACHE_STATSLOG"
}
