// divcoll: command-line entry point (filled in by the CLI work)
#include <cstdio>
int main() { std::puts("divcoll"); return 0; }
