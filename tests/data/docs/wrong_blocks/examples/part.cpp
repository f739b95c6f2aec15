int twice(int x) {
  const int y = 2 * x;
  return y;
}
