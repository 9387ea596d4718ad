#version 450
// Shadow maps store depth only.
void main() {}
