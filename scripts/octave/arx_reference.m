## Octave's reference ARX estimates for tests/core/arx_octave_test.cc.
## Reads tests/data/octave/arx_input.csv (columns time_s,u1,u2,y), runs the control package's
## `arx` (control 3.4.0) for several orders and writes tests/data/octave/arx_expected.csv with one
## row per parameter:  case,na,nb1,nb2,nk,first_sample,index,value
##   nk           the delay in MATLAB's convention (canalid's), the same for both inputs
##   first_sample 0-based index of the first equation Octave uses (see below)
##   index        0-based position in theta = [a_1..a_na, b_1.. of u1, b_1.. of u2]
##
## Conventions of Octave's arx (read from /usr/share/octave/packages/control-3.4.0/arx.m and
## @iddata/nkshift.m; checked on noise-free data):
##  * Octave's 'nk' is MATLAB's nk - 1: with nk = 0 the regressors are u(t-1)..u(t-nb), and the
##    numerator is returned as [0, zeros(1, nk), b_1 .. b_nb].  We pass nk - 1.
##  * no demeaning or detrending.
##  * 'nk' > 0 is applied by nkshift (drops the first nk samples of y and the last nk of u), then
##    the equations run over t = max(na, max(nb)) + 1 .. N of the shifted data.  In the original
##    indexing (1-based) the first equation is t = max(na, max(nb)) + nk_octave + 1, whereas the
##    first sample whose regressors all exist (canalid's default) is max(na, max(nb) + nk - 1) + 1.
##    They differ when na > max(nb) and nk_octave > 0; the C++ test passes this first_sample to
##    FitArx so both solve the same least-squares problem.
##  * the estimate is solved as Octave's "square-root algorithm": QR of [Phi, Y], then an SVD
##    solve of R1 theta = R2.
## Also prints the median time of arx(na=2, nb=2) on 100k samples.
## Run from the repository root:  octave --no-gui -q scripts/octave/arx_reference.m
pkg load control
data = dlmread ("tests/data/octave/arx_input.csv", ",", 1, 0);
u = data(:, 2:3);
y = data(:, 4);
dat = iddata (y, u, 1);

## Rows: na, nb1, nb2, nk (MATLAB convention).
cases = [2, 2, 2, 1;
         3, 2, 3, 2;
         4, 2, 2, 3;
         1, 3, 1, 1];
fid = fopen ("tests/data/octave/arx_expected.csv", "w");
fprintf (fid, "case,na,nb1,nb2,nk,first_sample,index,value\n");
for c = 1:rows (cases)
  na = cases(c, 1); nb = cases(c, 2:3); nk = cases(c, 4);
  sys = arx (dat, "na", na, "nb", nb, "nk", nk - 1);
  [num, den] = filtdata (sys);
  a = den{1, 1}(2:end);
  b1 = num{1, 1}(nk + 1 : nk + nb(1));
  b2 = num{1, 2}(nk + 1 : nk + nb(2));
  ## sanity: leading zeros are exactly the delay, and the lengths match the orders
  assert (all (num{1, 1}(1:nk) == 0) && numel (a) == na);
  theta = [a(:); b1(:); b2(:)];
  first_sample = max (na, max (nb)) + (nk - 1);   # 0-based
  for i = 1:numel (theta)
    fprintf (fid, "%d,%d,%d,%d,%d,%d,%d,%.17g\n", c - 1, na, nb(1), nb(2), nk, first_sample, ...
             i - 1, theta(i));
  endfor
endfor
fclose (fid);

## Timing: single input, na = nb = 2, nk = 1 (Octave nk = 0), 100k samples.
randn ("state", 1);
n = 100000;
ut = randn (n, 1);
yt = filter ([0, 0.8, 0.3], [1, -1.2, 0.35], ut) + 0.05 * randn (n, 1);
dt = iddata (yt, ut, 1);
## Wall time (tic/toc) and process CPU time (cputime): on a shared machine the CPU time is the
## steadier figure.
runs = 15;
wall = zeros (runs, 1);
cpu = zeros (runs, 1);
for r = 1:runs
  c0 = cputime ();
  tic;
  arx (dt, "na", 2, "nb", 2);
  wall(r) = toc;
  cpu(r) = cputime () - c0;
endfor
printf ("octave %s control %s arx(na=2,nb=2) on %d samples, %d runs: wall median %.4f s (min %.4f), cpu median %.4f s (min %.4f)\n",
        OCTAVE_VERSION, pkg ("describe", "control"){1}.version, n, runs, median (wall), min (wall),
        median (cpu), min (cpu));
