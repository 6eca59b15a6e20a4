//! Image I/O (EXR, PNG), tone mapping, heatmaps and error metrics (RMSE, relMSE, PSNR, SSIM, FLIP) for caustics-bench.
