// mltfarm command line (subcommands are added by their owners).
#include <cstdio>
int main() { std::puts("mltfarm: no subcommands yet"); return 0; }
