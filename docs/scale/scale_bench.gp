set terminal pngcairo size 1200,500 noenhanced
set key outside bottom center horizontal font ',9'
set grid
set xlabel 'ranks (mpirun -np; single process at 1)'
set xtics 1
set xrange [0.5:*]
set output '/work/main/docs/scale/scale_time.png'
set multiplot layout 1,2 title 'isoscope mesh: out of core (budget 1024 MiB) and MPI, iso 300.5; vtkFlyingEdges3D holds the whole volume'
set title 'wall time (lower is better)'
set ylabel 's'
set yrange [0:*]
plot '/work/main/docs/scale/scale_series0.dat' using 1:2 with points pt 9 ps 2 title 'isoscope ct1024x1024x1024', '/work/main/docs/scale/scale_series1.dat' using 1:2 with points pt 9 ps 2 title 'isoscope ct2048x2048x1024', '/work/main/docs/scale/scale_series2.dat' using 1:2 with linespoints pt 5 lw 2 title 'isoscope-mpi ct1024x1024x1024', '/work/main/docs/scale/scale_series3.dat' using 1:2 with linespoints pt 5 lw 2 title 'isoscope-mpi ct2048x2048x1024', '/work/main/docs/scale/scale_series4.dat' using 1:2 with points pt 7 ps 2 title 'vtkFlyingEdges3D ct1024x1024x1024'
set title 'throughput (higher is better)'
set ylabel 'Mvoxel/s'
plot '/work/main/docs/scale/scale_series0.dat' using 1:3 with points pt 9 ps 2 title 'isoscope ct1024x1024x1024', '/work/main/docs/scale/scale_series1.dat' using 1:3 with points pt 9 ps 2 title 'isoscope ct2048x2048x1024', '/work/main/docs/scale/scale_series2.dat' using 1:3 with linespoints pt 5 lw 2 title 'isoscope-mpi ct1024x1024x1024', '/work/main/docs/scale/scale_series3.dat' using 1:3 with linespoints pt 5 lw 2 title 'isoscope-mpi ct2048x2048x1024', '/work/main/docs/scale/scale_series4.dat' using 1:3 with points pt 7 ps 2 title 'vtkFlyingEdges3D ct1024x1024x1024'
unset multiplot
set output '/work/main/docs/scale/scale_memory.png'
set terminal pngcairo size 900,550 noenhanced
set title 'peak resident memory per rank (solid) and total (dashed) vs the budget'
set ylabel 'MiB'
set yrange [0:*]
plot 1024 with lines lc 'black' lw 2 title 'budget 1024 MiB', 1280 with lines lc 'black' dt 2 title 'budget + 256 MiB', '/work/main/docs/scale/scale_series0.dat' using 1:4 with points pt 9 ps 2 lc 1 title 'isoscope ct1024x1024x1024 per rank', '' using 1:5 with linespoints dt 2 lc 1 title 'total', '/work/main/docs/scale/scale_series1.dat' using 1:4 with points pt 9 ps 2 lc 2 title 'isoscope ct2048x2048x1024 per rank', '' using 1:5 with linespoints dt 2 lc 2 title 'total', '/work/main/docs/scale/scale_series2.dat' using 1:4 with linespoints pt 5 lw 2 lc 3 title 'isoscope-mpi ct1024x1024x1024 per rank', '' using 1:5 with linespoints dt 2 lc 3 title 'total', '/work/main/docs/scale/scale_series3.dat' using 1:4 with linespoints pt 5 lw 2 lc 4 title 'isoscope-mpi ct2048x2048x1024 per rank', '' using 1:5 with linespoints dt 2 lc 4 title 'total', '/work/main/docs/scale/scale_series4.dat' using 1:4 with points pt 7 ps 2 lc 5 title 'vtkFlyingEdges3D ct1024x1024x1024 per rank', '' using 1:5 with linespoints dt 2 lc 5 title 'total'
