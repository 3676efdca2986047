# Sourced by scripts/build, scripts/fuzz and scripts/sanitize (not run on its own): when ccache is
# installed, sets the array `launcher` to the CMake option that compiles through it, with paths
# made relative to the checkout's parent so that checkouts of the tree share objects; else
# leaves it empty. Expects `root` (the checkout).
launcher=()
if command -v ccache >/dev/null 2>&1; then
  export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$(dirname "$root")} CCACHE_NOHASHDIR=1
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
