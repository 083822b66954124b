"""The paper's analyses as tools: response diagrams, deconvolution, domain contrast."""
