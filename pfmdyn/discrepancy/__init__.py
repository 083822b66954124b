"""Where the paper's model and a measurement disagree, and which effect is missing."""
