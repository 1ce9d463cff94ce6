"""Scripts behind the impact study of issue 15 (verification/results/impact_pressure/README.md): probe
series per run, spectra and band content, the metrics recomputed from saved series, the study table."""
