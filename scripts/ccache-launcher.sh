# Sourced by scripts/build, scripts/fuzz and scripts/sanitize (not run on its own): when ccache is
# installed, sets the array `launcher` to the CMake option that compiles through it, with paths
# made relative to the checkout's parent so that checkouts of the tree share objects; else
# leaves it empty. Expects `root` (the checkout).
# The settings ride in the launcher itself (env VAR=... ccache), not in this shell's environment:
# a `ninja` run by hand in the build tree must compute the same keys, or what it stores is found
# by no other checkout (a CI clone missed 125 of 249 compiles that way).
launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=("-DCMAKE_CXX_COMPILER_LAUNCHER=env;CCACHE_BASEDIR=$(dirname "$root");CCACHE_NOHASHDIR=1;ccache")
fi
