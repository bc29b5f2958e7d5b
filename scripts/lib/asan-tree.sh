# Sourced by ci-fuzz.sh and ci-sanitize.sh (issue 41): the one AddressSanitizer + UBSan build
# tree (clang, -O1, line tables) that serves both the libFuzzer targets and the sanitizer test
# run. The libraries carry libFuzzer's coverage instrumentation (SEMAP_BUILD_FUZZ), the tests
# do not. Both scripts configure it with the same arguments, so the second finds it up to date.
# Without precompiled headers: with clang, a PCH defeats ccache in every clone but the one that
# filled the cache. The PCH is named by an absolute path that ccache does not rewrite
# (`-Xclang -include -Xclang /CLONE/build-asan/.../cmake_pch.hxx`, hashed as given) and the .pch
# file itself embeds the clone's paths, so each TU that uses it misses in a fresh clone (a clean-
# clone CI run took 12 % of this tree from the cache). Without it, ccache serves a fresh clone.
ASAN_BUILD=${SEMAP_ASAN_BUILD:-build-asan}
configure_asan_tree() {
  CC=clang CXX=clang++ cmake -S . -B "$ASAN_BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -DNDEBUG" \
    -DSEMAP_SANITIZE=address,undefined -DSEMAP_BUILD_FUZZ=ON -DSEMAP_BUILD_TESTS=ON \
    -DSEMAP_BUILD_BENCH=OFF -DSEMAP_BUILD_PYTHON=OFF -DSEMAP_WITH_OPEN3D=OFF -DSEMAP_PRECOMPILE_HEADERS=OFF >/dev/null
}
