set terminal pngcairo size 640,560 font ',10'
set output 'bench-out/ao/ao_time_rmse_ct-bone_R10.png'
set logscale x
set grid
set key bottom left
set xlabel 'AO time per frame, ms'
set ylabel 'RMSE'
set yrange [0:*]
set label 1 'llvmpipe (LLVM 15.0.6; 256 bits)' at graph 0.02, graph 0.97 font ',8'
set title 'ct-bone, R = 10'
plot 'bench-out/ao/ao_time_rmse.dat' index 6 with points pt 7 ps 1.2 lc rgb '#1f77b4' title 'cone 256', 'bench-out/ao/ao_time_rmse.dat' index 7 with lines lc rgb '#1f77b4' notitle, 'bench-out/ao/ao_time_rmse.dat' index 8 with points pt 5 ps 1.2 lc rgb '#d62728' title 'disk 256', 'bench-out/ao/ao_time_rmse.dat' index 9 with lines lc rgb '#d62728' notitle, 'bench-out/ao/ao_time_rmse.dat' index 10 with points pt 9 ps 1.2 lc rgb '#2ca02c' title 'SSAO 256', 'bench-out/ao/ao_time_rmse.dat' index 11 with lines lc rgb '#2ca02c' notitle, 0.166184 with lines dt 2 lc rgb 'gray40' title 'no AO'
