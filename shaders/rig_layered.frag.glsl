// The layered-rendering experiment: depth only.
void main() {}
