// report sweep (being written)
