"""The paper's figures and tables from a run file, one module per figure (each also a script in postprocess/:
fig2.py is divcoll_post.figures.fig2); each has main(argv) and draws with matplotlib's Agg backend."""
