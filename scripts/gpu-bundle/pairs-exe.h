// Force-included (-include) into the GPU bundle's build by scripts/gpu-run.sh: the GL tests run cullide-pairs
// through std::system(), and the build tree's absolute path would not exist on the GPU machine. The bundle's
// run.sh puts its bin/ first on PATH, so the plain name finds the bundle's copy.
#undef CULLIDE_PAIRS_EXE
#define CULLIDE_PAIRS_EXE "cullide-pairs"
