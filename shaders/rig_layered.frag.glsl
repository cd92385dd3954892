// issue 14, the layered-rendering experiment: depth only.
void main() {}
