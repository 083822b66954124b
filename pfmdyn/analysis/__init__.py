"""The analyses that compute from data and the generated relations: response diagrams
(:mod:`.diagram`), deconvolution of electrostatic and electromechanical parts
(:mod:`.deconvolve`), domain contrast (:mod:`.domains`), contact stiffness from resonances
(:mod:`.stiffness`) and thermal-tune peaks, with the resonance table of an instrument file
(:mod:`.thermal`)."""
