#include <stdio.h>
int main(void) { puts("woven"); return 0; }
