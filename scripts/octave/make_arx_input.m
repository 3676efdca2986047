## Writes tests/data/octave/arx_input.csv: a seeded 2-input ARX record with equation noise,
##   y(t) - 1.2 y(t-1) + 0.35 y(t-2) = 0.8 u1(t-1) + 0.3 u1(t-2) + 0.5 u2(t-2) - 0.2 u2(t-3) + e(t)
## u1 a random binary +-1 signal held 3 samples, u2 white Gaussian, e ~ N(0, 0.05^2), N = 3000.
## Run from the repository root:  octave --no-gui -q scripts/octave/make_arx_input.m
N = 3000;
randn ("state", 20261121);
rand ("state", 20261121);
bits = sign (rand (ceil (N / 3), 1) - 0.5);
u1 = kron (bits, ones (3, 1))(1:N);
u2 = randn (N, 1);
e = 0.05 * randn (N, 1);
y = zeros (N, 1);
for t = 1:N
  acc = e(t);
  if (t > 1) acc += 1.2 * y(t-1) + 0.8 * u1(t-1); endif
  if (t > 2) acc += -0.35 * y(t-2) + 0.3 * u1(t-2) + 0.5 * u2(t-2); endif
  if (t > 3) acc += -0.2 * u2(t-3); endif
  y(t) = acc;
endfor
fid = fopen ("tests/data/octave/arx_input.csv", "w");
fprintf (fid, "time_s,u1,u2,y\n");
fprintf (fid, "%d,%.17g,%.17g,%.17g\n", [(0:N-1)', u1, u2, y]');
fclose (fid);
