"""The paper's figures and tables from a run file, one module per figure, each a command line too
(`python3 -m divcoll_post.figures.fig2 RUN.h5`); each has main(argv) and draws with matplotlib's Agg backend."""
