"""The noisy-TV test's instruments (``results/noisy_tv/instrument/``)."""
