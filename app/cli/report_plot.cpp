// report plot (being written)
