set terminal pngcairo size 2160,620 font ',10'
set output 'bench-out/ao/ao_time_rmse.png'
set multiplot layout 1,4 title 'Ambient occlusion: run time against RMSE (Embree reference), llvmpipe (LLVM 15.0.6; 256 bits)'
set logscale x
set grid
set key bottom left
set xlabel 'AO time per frame, ms'
set ylabel 'RMSE'
set yrange [0:*]
set title 'ct-skin, R = 10'
plot 'bench-out/ao/ao_time_rmse.dat' index 0 with points pt 7 ps 1.2 lc rgb '#1f77b4' title 'cone 256', 'bench-out/ao/ao_time_rmse.dat' index 1 with lines lc rgb '#1f77b4' notitle, 'bench-out/ao/ao_time_rmse.dat' index 2 with points pt 5 ps 1.2 lc rgb '#d62728' title 'disk 256', 'bench-out/ao/ao_time_rmse.dat' index 3 with lines lc rgb '#d62728' notitle, 'bench-out/ao/ao_time_rmse.dat' index 4 with points pt 9 ps 1.2 lc rgb '#2ca02c' title 'SSAO 256', 'bench-out/ao/ao_time_rmse.dat' index 5 with lines lc rgb '#2ca02c' notitle, 0.0895984 with lines dt 2 lc rgb 'gray40' title 'no AO'
set title 'ct-bone, R = 10'
plot 'bench-out/ao/ao_time_rmse.dat' index 6 with points pt 7 ps 1.2 lc rgb '#1f77b4' title 'cone 256', 'bench-out/ao/ao_time_rmse.dat' index 7 with lines lc rgb '#1f77b4' notitle, 'bench-out/ao/ao_time_rmse.dat' index 8 with points pt 5 ps 1.2 lc rgb '#d62728' title 'disk 256', 'bench-out/ao/ao_time_rmse.dat' index 9 with lines lc rgb '#d62728' notitle, 'bench-out/ao/ao_time_rmse.dat' index 10 with points pt 9 ps 1.2 lc rgb '#2ca02c' title 'SSAO 256', 'bench-out/ao/ao_time_rmse.dat' index 11 with lines lc rgb '#2ca02c' notitle, 0.166184 with lines dt 2 lc rgb 'gray40' title 'no AO'
set title 'bunny, R = 0.0500'
plot 'bench-out/ao/ao_time_rmse.dat' index 12 with points pt 7 ps 1.2 lc rgb '#1f77b4' title 'cone 256', 'bench-out/ao/ao_time_rmse.dat' index 13 with lines lc rgb '#1f77b4' notitle, 'bench-out/ao/ao_time_rmse.dat' index 14 with points pt 5 ps 1.2 lc rgb '#d62728' title 'disk 256', 'bench-out/ao/ao_time_rmse.dat' index 15 with lines lc rgb '#d62728' notitle, 'bench-out/ao/ao_time_rmse.dat' index 16 with points pt 9 ps 1.2 lc rgb '#2ca02c' title 'SSAO 256', 'bench-out/ao/ao_time_rmse.dat' index 17 with lines lc rgb '#2ca02c' notitle, 0.064971 with lines dt 2 lc rgb 'gray40' title 'no AO'
set title 'thin, R = 10'
plot 'bench-out/ao/ao_time_rmse.dat' index 18 with points pt 7 ps 1.2 lc rgb '#1f77b4' title 'cone 256', 'bench-out/ao/ao_time_rmse.dat' index 19 with lines lc rgb '#1f77b4' notitle, 'bench-out/ao/ao_time_rmse.dat' index 20 with points pt 5 ps 1.2 lc rgb '#d62728' title 'disk 256', 'bench-out/ao/ao_time_rmse.dat' index 21 with lines lc rgb '#d62728' notitle, 'bench-out/ao/ao_time_rmse.dat' index 22 with points pt 9 ps 1.2 lc rgb '#2ca02c' title 'SSAO 256', 'bench-out/ao/ao_time_rmse.dat' index 23 with lines lc rgb '#2ca02c' notitle, 0.19321 with lines dt 2 lc rgb 'gray40' title 'no AO'
unset multiplot
