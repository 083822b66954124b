"""Reading data: measured spectra and resonance tables (CSV) and instrument files."""
