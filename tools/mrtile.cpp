// The mrtile command-line tool (work in progress).
#include <cstdio>
int main() { std::puts("mrtile " MRTILE_VERSION); return 0; }
